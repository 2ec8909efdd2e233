// The springy command as a user runs it: exit codes, messages, and output files that are
// complete or absent.
#include <gtest/gtest.h>

#include "run_springy.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

namespace {

namespace fs = std::filesystem;

using Result = springy::test::CommandResult;
Result run(const std::string& args) { return springy::test::runSpringy(args); }

std::string data(const std::string& name) { return std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/" + name; }

class AppTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("springy_app_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::size_t filesIn(const fs::path& d) const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(d), fs::directory_iterator{}));
  }
  fs::path dir_;
};

// The shared libraries a program loads (ldd), one name per line.
std::string sharedLibraries(const std::string& program) {
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen(("ldd " + program + " 2>&1").c_str(), "r"), ::pclose);
  std::array<char, 4096> buffer{};
  while (pipe && std::fgets(buffer.data(), buffer.size(), pipe.get())) out += buffer.data();
  return out;
}

TEST(Program, SpringyLoadsNoDrawingLibrariesAndRenderRunsBesideIt) {
  // OSMesa (with LLVM) and FFmpeg bring about 150 shared libraries, which took 60 ms to load and
  // start at every command (a 2562-vertex ball's whole check takes 220 ms on one thread): springy
  // links neither, and render and frames run springy-render from its directory.
  const std::string springy = sharedLibraries(SPRINGY_BINARY);
  ASSERT_NE(springy.find("libc.so"), std::string::npos) << springy;
  EXPECT_EQ(springy.find("OSMesa"), std::string::npos) << springy;
  EXPECT_EQ(springy.find("libavcodec"), std::string::npos) << springy;
  const fs::path helper = fs::path(SPRINGY_BINARY).parent_path() / "springy-render";
  EXPECT_NE(sharedLibraries(helper.string()).find("OSMesa"), std::string::npos);
  // A bad argument of render is refused with its message, exit status and all, through the helper.
  const Result bad = run("render " + data("tiny.toml") + " --width 7");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("width"), std::string::npos) << bad.output;
}

TEST_F(AppTest, CheckPassesAStableSceneAndReportsPerBody) {
  const Result r = run("check " + data("tiny.toml"));
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("ball"), std::string::npos);
  EXPECT_NE(r.output.find("ok"), std::string::npos);
}

TEST_F(AppTest, CheckNamesTheBodyStepAndRemedyOfABlowUp) {
  const Result r = run("check " + data("unstable.toml"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("body 'stiff ball' at step"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("smaller dt"), std::string::npos) << r.output;
}

TEST_F(AppTest, VolumeLimitsFailACollapsingBody) {
  // The tiny ball squashes on landing: a 99.9% floor is broken mid-run, and a 99.99% end
  // requirement after a short run is not met either; 50% passes.
  Result r = run("check " + data("tiny.toml") + " --min-volume 0.999");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("its volume fell to"), std::string::npos) << r.output;
  r = run("check " + data("tiny.toml") + " --end-volume 0.99999");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("of its rest volume, below the required"), std::string::npos) << r.output;
  r = run("check " + data("tiny.toml") + " --min-volume 0.5 --end-volume 0.5");
  EXPECT_EQ(r.status, 0) << r.output;
}

TEST_F(AppTest, AClothHasNoVolumeToReportOrCheck) {
  // Its volume columns read "-" (they divided by its rest volume, 0), and the volume limits pass
  // it by while still holding the ball to them.
  const Result r = run("check " + data("cloth.toml") + " --min-volume 0.5 --end-volume 0.5");
  EXPECT_EQ(r.status, 0) << r.output;
  const std::size_t row = r.output.find("\n  cloth ");
  ASSERT_NE(row, std::string::npos) << r.output;
  const std::string line = r.output.substr(row + 1, r.output.find('\n', row + 1) - row - 1);
  EXPECT_NE(line.find(" - "), std::string::npos) << line;
  for (const char* bad : {"nan", "inf"}) EXPECT_EQ(r.output.find(bad), std::string::npos) << r.output;
  const Result ball = run("check " + data("cloth.toml") + " --end-volume 0.99999");
  EXPECT_EQ(ball.status, 1) << ball.output;
  EXPECT_NE(ball.output.find("body 'ball' ends at"), std::string::npos) << ball.output;
}

TEST_F(AppTest, EndAtRestFailsAMovingBodyAndPassesAStillOne) {
  // The tiny ball is still bouncing when its 1 s scene ends; the resting ball, set down on
  // the ground and damped, is still through its last second.
  Result r = run("check " + data("tiny.toml") + " --end-at-rest");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("body 'ball' is not at rest at the end: in the last 1 s its vertex"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("(0.2% of its size)"), std::string::npos) << r.output;
  r = run("check " + data("tiny.toml"));  // without the flag, motion at the end is no failure
  EXPECT_EQ(r.status, 0) << r.output;
  r = run("check " + data("resting.toml") + " --end-at-rest");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(" yes\n"), std::string::npos) << r.output;  // the report's rest column
}

TEST_F(AppTest, UnknownSceneKeyIsReportedWithFileAndLine) {
  const Result r = run("check " + data("typo.toml"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("typo.toml:6:1: unknown key 'masss'"), std::string::npos) << r.output;
}

TEST_F(AppTest, TraceIsWrittenWithOneRowPerFrameAndBody) {
  const fs::path trace = dir_ / "trace.csv";
  const Result r = run("check " + data("tiny.toml") + " --trace " + trace.string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(trace);
  std::string line;
  int rows = -1;  // header
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 10);  // 1 s at 10 frames/s, one body
  EXPECT_EQ(filesIn(dir_), 1u);
}

// A scene that gives no step runs at the advisor's default, and check's run is its try: the
// trace holds that run's rows, one per frame and body, written once the run passed.
TEST_F(AppTest, TheDefaultStepsTryIsTheTracedRun) {
  const fs::path trace = dir_ / "trace.csv";
  const Result r = run("check " + data("cloth.toml") + " --trace " + trace.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("this run is its try"), std::string::npos) << r.output;
  std::ifstream in(trace);
  std::string line;
  int rows = -1;  // header
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 10);  // 0.5 s at 10 frames/s, two bodies
}

// A duration under half a frame still runs one frame, as `render` draws one (it ran no step and
// said "ok").
TEST_F(AppTest, ADurationUnderHalfAFrameRunsOneFrame) {
  const Result r = run("check " + data("tiny.toml") + " --duration 0.01");  // frames of 0.1 s, steps of 5 ms
  ASSERT_EQ(r.status, 0) << r.output;
  const std::size_t row = r.output.find("\n  ball ");
  ASSERT_NE(row, std::string::npos) << r.output;
  EXPECT_EQ(std::stoi(r.output.substr(row + 8)), 20) << r.output;  // one frame: 0.1 s / 0.005 s
}

// Names are the user's text: one with a comma or a quote is quoted in the trace (RFC 4180), so
// every row still has the header's twelve fields.
TEST_F(AppTest, TraceQuotesNamesThatHoldCommasOrQuotes) {
  std::ifstream tiny(data("tiny.toml"));
  std::string text((std::istreambuf_iterator<char>(tiny)), std::istreambuf_iterator<char>());
  text.replace(text.find("name = \"Tiny\""), 13, "name = 'Tiny, \"quoted\"'");
  text.replace(text.find("name = \"ball\""), 13, "name = \"ball, one\"");
  const fs::path scene = dir_ / "named.toml", trace = dir_ / "trace.csv";
  { std::ofstream(scene) << text; }
  const Result r = run("check " + scene.string() + " --trace " + trace.string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(trace);
  std::string header, row;
  ASSERT_TRUE(std::getline(in, header) && std::getline(in, row));
  EXPECT_EQ(row.rfind("\"Tiny, \"\"quoted\"\"\",", 0), 0u) << row;
  EXPECT_NE(row.find(",\"ball, one\","), std::string::npos) << row;
  // Outside the quotes, as many commas as the header has.
  std::size_t commas = 0;
  bool quoted = false;
  for (const char c : row) {
    if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      ++commas;
  }
  EXPECT_EQ(commas, static_cast<std::size_t>(std::count(header.begin(), header.end(), ','))) << row;
}

TEST_F(AppTest, RenderWritesAVideoAndNoTemporaryFiles) {
  const fs::path out = dir_ / "tiny.mp4";
  const Result r = run("render " + data("tiny.toml") + " -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_GT(fs::file_size(out), 1000u);
  EXPECT_EQ(filesIn(dir_), 1u);
}

TEST_F(AppTest, UnstableRenderKeepsTheExistingFileAndLeavesNoTemporaryFile) {
  const fs::path out = dir_ / "video.mp4";
  { std::ofstream(out) << "a good video from before"; }
  const Result r = run("render " + data("unstable.toml") + " -o " + out.string());
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("not written"), std::string::npos) << r.output;
  std::ifstream in(out);
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(content, "a good video from before");
  EXPECT_EQ(filesIn(dir_), 1u);
}

TEST_F(AppTest, UnwritableTargetIsReportedBeforeSimulating) {
  const Result r = run("render " + data("tiny.toml") + " -o " + (dir_ / "no" / "such" / "dir" / "x.mp4").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("cannot write here"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("frames"), std::string::npos) << "simulation started: " << r.output;
}

TEST_F(AppTest, FramesWritesStillsAndASheet) {
  const Result r = run("frames " + data("tiny.toml") + " -o " + dir_.string() + " --times 0,0.5 --sheet");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir_ / "tiny_t000.00.png"));
  EXPECT_TRUE(fs::exists(dir_ / "tiny_t000.50.png"));
  EXPECT_TRUE(fs::exists(dir_ / "tiny_sheet.png"));
  EXPECT_EQ(filesIn(dir_), 3u);
}

// render and frames run a scene that gives no step once, as check does: the drawn run is the
// advisor's try of its default step (before, a separate try simulated the whole scene first).
TEST_F(AppTest, RenderRunsADefaultStepThatPassesOnce) {
  const fs::path out = dir_ / "cloth.mp4";
  const Result r = run("render " + data("cloth.toml") + " --width 96 --height 54 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("; this run is its try"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("over the whole run"), std::string::npos) << r.output;  // no separate try
  EXPECT_EQ(filesIn(dir_), 1u);
}

// The coarse bunny's default step (3 substeps) fails at its landing, t = 1.63 s: render draws the
// run again at the count that passed (6) into the same temporary file, and leaves only the whole
// video; no failure is reported, since the user gave no step.
TEST_F(AppTest, RenderDrawsAgainWhenTheDefaultStepsTryFails) {
  const fs::path out = dir_ / "bunny.mp4";
  const Result r = run("render " + data("bunny_coarse.toml") + " --width 96 --height 54 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("; this run is its try"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the run failed at 3 substeps (after t = 1.6"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the run passed at 6 substeps"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(out.string() + ": 53 frames, "), std::string::npos) << r.output;  // 1.75 s at 30/s
  EXPECT_GT(fs::file_size(out), 1000u);
  EXPECT_EQ(filesIn(dir_), 1u);  // nothing left of the first run
}

// frames likewise: the stills of the failed try are drawn again from the run that passed, over the
// same files; each is the one `--substeps 6` draws (t = 1.0 s, before the failure, too: a still
// of the failed run would differ).
TEST_F(AppTest, FramesDrawAgainWhenTheDefaultStepsTryFails) {
  const std::string common = "frames " + data("bunny_coarse.toml") + " --width 96 --height 54 --times 1,1.75 -o ";
  const fs::path given = dir_ / "given";
  const Result r = run(common + dir_.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("the run failed at 3 substeps (after t = 1.6"), std::string::npos) << r.output;
  const Result six = run(common + given.string() + " --substeps 6");
  ASSERT_EQ(six.status, 0) << six.output;
  for (const char* still : {"bunny_coarse_t001.00.png", "bunny_coarse_t001.75.png"}) {
    std::ifstream a(dir_ / still, std::ios::binary), b(given / still, std::ios::binary);
    const std::string drawn((std::istreambuf_iterator<char>(a)), std::istreambuf_iterator<char>());
    const std::string reference((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
    EXPECT_FALSE(drawn.empty()) << still;
    EXPECT_TRUE(drawn == reference) << still << " is not the still of the run at 6 substeps";
  }
  const Result three = run(common + (dir_ / "three").string() + " --substeps 3");
  EXPECT_EQ(three.status, 1) << three.output;  // the step the user gives is not retried
  EXPECT_NE(three.output.find("total energy rose"), std::string::npos) << three.output;
}

TEST_F(AppTest, BadTimesAreRejected) {
  const Result r = run("frames " + data("tiny.toml") + " -o " + dir_.string() + " --times 0,abc");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("'abc' is not a time"), std::string::npos) << r.output;
}

}  // namespace

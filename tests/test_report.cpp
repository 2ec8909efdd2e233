// springy report: its folder appears complete or not at all, an earlier report of springy's is
// replaced and anything else is left alone, bad input is a clear error before any run, and the
// pages say what check says. (The pages in a browser: tests/report_test.sh, ctest report_browser.)
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "springy_process.h"

namespace {

namespace fs = std::filesystem;
using springy::test::Clock;
using springy::test::Result;
using springy::test::Springy;

const std::string kData = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/";
const std::string kTiny = kData + "app/tiny.toml";

std::string text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool has(const std::string& haystack, const std::string& needle) { return haystack.find(needle) != std::string::npos; }

class ReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("springy_report_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static Result run(const std::vector<std::string>& args) { return Springy(args, {}).wait(120.0); }
  // The names in the test's folder (hidden ones too: a temporary folder left behind shows).
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& e : fs::directory_iterator(dir_)) n.push_back(e.path().filename().string());
    std::sort(n.begin(), n.end());
    return n;
  }
  fs::path dir_;
};

TEST_F(ReportTest, WritesTheFolderAndItsPages) {
  const fs::path out = dir_ / "report";
  const Result r = run({"report", kTiny, "-o", out.string()});
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(has(r.output, "report: wrote " + out.string() + "/index.html")) << r.output;
  for (const char* file : {"index.html", ".springy-report", "assets/viewer.js", "assets/report.css", "tiny/index.html",
                           "tiny/tiny.mp4", "tiny/tiny_sheet.png", "tiny/replay.js", "tiny/trace.csv",
                           "tiny/check.json", "tiny/energy.svg", "tiny/volume.svg", "tiny/strain.svg",
                           "tiny/contacts.svg", "tiny/scene.toml"}) {
    EXPECT_TRUE(fs::is_regular_file(out / file) && fs::file_size(out / file) > 0) << file;
  }
  EXPECT_EQ(names(), std::vector<std::string>{"report"});  // no temporary folder left
  // The viewer is three.js, bundled (its licence kept), and the page loads it after its replay.
  EXPECT_TRUE(has(text(out / "assets/viewer.js"), "Three.js Authors"));
  const std::string page = text(out / "tiny/index.html");
  EXPECT_LT(page.find("src=\"replay.js\""), page.find("src=\"../assets/viewer.js\""));
  // The page's table says what check's records say.
  const nlohmann::json records = nlohmann::json::parse(text(out / "tiny/check.json"));
  const auto& body = records["scenes"][0]["bodies"][0];
  EXPECT_EQ(records["scenes"][0]["status"], "ok");
  char steps[32];
  std::snprintf(steps, sizeof steps, "<td>%llu</td>", static_cast<unsigned long long>(body["steps"].get<uint64_t>()));
  EXPECT_TRUE(has(page, steps)) << steps;
  char volume[32];
  std::snprintf(volume, sizeof volume, ">%.3f</td>", body["volume_min"].get<double>());
  EXPECT_TRUE(has(page, volume)) << volume;
  // The trace gained a column: the vertices in contact, none while the ball falls (it starts 1 m
  // above the ground: it lands at 0.45 s), some once it lands.
  std::istringstream trace(text(out / "tiny/trace.csv"));
  std::string line;
  std::getline(trace, line);
  EXPECT_TRUE(has(line, ",max_strain,contacts")) << line;
  std::vector<int> contacts;
  while (std::getline(trace, line)) contacts.push_back(std::stoi(line.substr(line.rfind(',') + 1)));
  ASSERT_EQ(contacts.size(), 10u);
  EXPECT_EQ(contacts[0], 0);
  EXPECT_GT(*std::max_element(contacts.begin(), contacts.end()), 0);
}

TEST_F(ReportTest, AnUnstableSceneGetsItsPageAndTheExitStatusSaysSo) {
  const fs::path out = dir_ / "report";
  const Result r = run({"report", kTiny, kData + "app/unstable.toml", "-o", out.string()});
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_TRUE(has(r.output, "blew up")) << r.output;
  const std::string page = text(out / "unstable/index.html");
  EXPECT_TRUE(has(page, "blew up")) << page;
  EXPECT_TRUE(has(page, "No video")) << page;
  EXPECT_FALSE(fs::exists(out / "unstable/unstable.mp4"));  // no video of garbage
  EXPECT_FALSE(fs::exists(out / "unstable/replay.js"));
  EXPECT_TRUE(fs::exists(out / "tiny/tiny.mp4"));
  const std::string index = text(out / "index.html");
  EXPECT_TRUE(has(index, "class=\"bad\">failed")) << index;
  EXPECT_TRUE(has(index, "class=\"ok\">ok")) << index;
}

TEST_F(ReportTest, RefusesAFolderThatSpringyDidNotWrite) {
  const fs::path out = dir_ / "mine";
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "my notes";
  const Result r = run({"report", kTiny, "-o", out.string()});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(has(r.output, out.string() + " exists, is not empty and was not written by springy")) << r.output;
  EXPECT_FALSE(has(r.output, "steps")) << "ran before refusing: " << r.output;
  EXPECT_EQ(text(out / "notes.txt"), "my notes");
  EXPECT_EQ(names(), std::vector<std::string>{"mine"});
  // An empty folder is taken (mkdir first, report into it).
  const fs::path empty = dir_ / "empty";
  fs::create_directories(empty);
  EXPECT_EQ(run({"report", kTiny, "-o", empty.string()}).status, 0);
  EXPECT_TRUE(fs::exists(empty / "index.html"));
}

TEST_F(ReportTest, AnUnwritablePlaceIsAClearErrorBeforeAnyRun) {
  std::ofstream(dir_ / "file") << "x";
  struct Case {
    fs::path out;
    std::string says;
  };
  for (const Case& c : {Case{dir_ / "file" / "report", "cannot create a folder in " + (dir_ / "file").string()},
                        Case{dir_ / "missing" / "report", "cannot create a folder in " + (dir_ / "missing").string()},
                        Case{dir_ / "file", (dir_ / "file").string() + " exists and is not a folder"}}) {
    const Result r = run({"report", kTiny, "-o", c.out.string()});
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_TRUE(has(r.output, c.says)) << r.output;
    EXPECT_FALSE(has(r.output, "steps")) << "ran before failing: " << r.output;
  }
  EXPECT_EQ(names(), std::vector<std::string>{"file"});
}

TEST_F(ReportTest, ReplacesItsOwnReportWhole) {
  const fs::path out = dir_ / "report";
  ASSERT_EQ(run({"report", kTiny, "-o", out.string()}).status, 0);
  // A file springy did not write stops it before it runs (issue 63: a user's file is never lost)...
  std::ofstream(out / "stale.txt") << "from before";
  Result r = run({"report", kTiny, "-o", out.string(), "--duration", "0.5"});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(has(r.output, (out / "stale.txt").string())) << r.output;
  EXPECT_FALSE(has(r.output, "steps")) << "ran before refusing: " << r.output;
  EXPECT_EQ(text(out / "stale.txt"), "from before");
  // ...and without it the new report replaces the earlier one whole.
  fs::remove(out / "stale.txt");
  r = run({"report", kTiny, "-o", out.string(), "--duration", "0.5"});
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(has(text(out / "tiny/index.html"), "0.5 s")) << text(out / "tiny/index.html");
  EXPECT_EQ(names(), std::vector<std::string>{"report"});
}

TEST_F(ReportTest, CtrlCLeavesTheEarlierReportAsItWas) {
  const fs::path out = dir_ / "report";
  ASSERT_EQ(run({"report", kTiny, "-o", out.string()}).status, 0);
  const std::string before = text(out / "tiny/index.html");
  Springy s({"report", kTiny, "-o", out.string(), "--duration", "600"}, {});
  // Interrupted once its temporary folder exists and a little later.
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (names().size() < 2 && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(names().size(), 2u) << "no temporary folder appeared";
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  s.signal(SIGINT);
  const Result r = s.wait(60.0);
  EXPECT_EQ(r.status, 128 + SIGINT) << r.output;
  EXPECT_EQ(names(), std::vector<std::string>{"report"});
  EXPECT_EQ(text(out / "tiny/index.html"), before);
}

TEST_F(ReportTest, BadArgumentsAreClearErrors) {
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const fs::path sweep = dir_ / "not-a-sweep";
  fs::create_directories(sweep);
  fs::copy_file(kTiny, dir_ / "tiny.toml");  // another scene file of the same name
  const std::vector<Case> cases = {
      {{"report", "-o", (dir_ / "r").string()}, "give scenes, --sweep DIR or --study DIR"},
      {{"report", "--sweep", sweep.string(), "-o", (dir_ / "r").string()}, "no table.json there"},
      {{"report", "--study", sweep.string(), "-o", (dir_ / "r").string()}, "no study's pages (.md) there"},
      {{"report", kTiny, (dir_ / "tiny.toml").string(), "-o", (dir_ / "r").string()}, "share the name tiny"},
  };
  for (const Case& c : cases) {
    const Result r = run(c.args);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_TRUE(has(r.output, c.says)) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "r"));
  }
}

TEST_F(ReportTest, ASweepsPageHasARowPerTaskAndItsPlot) {
  const fs::path sweep = dir_ / "tiny.sweep";
  ASSERT_EQ(run({"sweep", kData + "report/sweep.toml", "-o", sweep.string()}).status, 0);
  const fs::path out = dir_ / "report";
  const Result r = run({"report", "--sweep", sweep.string(), "-o", out.string(), "--y", "max_strain"});
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string page = text(out / "sweep/index.html");
  const nlohmann::json table = nlohmann::json::parse(text(sweep / "table.json"));
  ASSERT_EQ(table["tasks"].size(), 4u);
  for (const auto& task : table["tasks"]) {
    const std::string status = task["status"];
    char row[64];
    std::snprintf(row, sizeof row, "task-%04d.html\">%d</a>", task["task"].get<int>(), task["task"].get<int>());
    EXPECT_TRUE(has(page, row)) << row;
    std::snprintf(row, sizeof row, "task-%04d.html", task["task"].get<int>());
    EXPECT_TRUE(has(text(out / "sweep" / row), status));
  }
  EXPECT_TRUE(has(page, "max_strain against dt")) << page;  // the first swept key across
  EXPECT_TRUE(fs::file_size(out / "sweep/sweep.svg") > 1000);
  const Result bad = run({"report", "--sweep", sweep.string(), "-o", out.string(), "--x", "nope"});
  EXPECT_EQ(bad.status, 1);
  EXPECT_TRUE(has(bad.output, "--x nope: the sweep has no such key (its keys: dt, body.strut_period)")) << bad.output;
}

}  // namespace

// springy and the processes it runs (issue 63): no name reaches a shell, no child outlives
// springy, every phase stops within a second of Ctrl-C or SIGTERM, and long work shows progress
// within seconds. Each test runs the real binary (tests/springy_process.h: fork/exec, signals).
#include <gtest/gtest.h>

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "springy_process.h"

namespace {

namespace fs = std::filesystem;
using springy::test::Clock;
using springy::test::Result;
using springy::test::Springy;

const std::string kSource = SPRINGY_SOURCE_DIR;
const std::string kTiny = kSource + "/tests/data/app/tiny.toml";

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A fresh directory, removed with what it holds; the test runs in it (springy's working directory).
class WorkDir {
 public:
  WorkDir() {
    std::string pattern = (fs::temp_directory_path() / "springy-processes-XXXXXX").string();
    path_ = ::mkdtemp(pattern.data());
    old_ = fs::current_path();
    fs::current_path(path_);
  }
  ~WorkDir() {
    fs::current_path(old_);
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_, old_;
};

// Every file named `name` under `dir`, and in the working directory.
std::vector<std::string> filesNamed(const fs::path& dir, const std::string& name) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.path().filename() == name) found.push_back(e.path().string());
  }
  return found;
}

// The process's children (Linux: /proc/PID/task/PID/children).
std::vector<pid_t> childrenOf(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) + "/children");
  std::vector<pid_t> children;
  for (pid_t child = 0; in >> child;) children.push_back(child);
  return children;
}

// Running, not ended: a zombie (ended, not yet reaped by whoever adopted it) counts as ended.
bool running(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  return close != std::string::npos && close + 2 < text.size() && text[close + 2] != 'Z';
}

// Waits up to `seconds` for `done`; true when it came.
template <class F>
bool within(double seconds, F done) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// Sends `signal` once `springy` has run `after` seconds, and waits for it: its result and the
// seconds it took to end after the signal.
std::pair<Result, double> stopAfter(Springy& springy, double after, int signal) {
  std::this_thread::sleep_for(std::chrono::duration<double>(after));
  const auto sent = Clock::now();
  springy.signal(signal);
  Result r = springy.wait(10.0);
  return {r, std::chrono::duration<double>(Clock::now() - sent).count()};
}

// The tiny scene running for 200 s at a small step (minutes of work), the ball named `ball`.
std::string longScene() {
  std::string text = readFile(kTiny);
  text.replace(text.find("duration = 1.0"), 14, "duration = 200.0");
  text.replace(text.find("dt = 0.005"), 10, "dt = 0.0005");
  return text;
}

// `n` soft balls 8 m apart, dropped 4 m: each loses most of its volume, so that suggest searches
// stiffer periods for every one.
std::string softBalls(int n) {
  std::string text = "[scene]\nname = \"balls\"\nduration = 2.0\ndt = 0.005\n";
  for (int i = 0; i < n; ++i) {
    text += "[[body]]\nname = \"b" + std::to_string(i) + "\"\nshape = \"icosphere\"\nsubdivisions = 1\nradius = 1.0\n" +
            "position = [" + std::to_string(8.0 * (i % 10)) + ", 4.0, " + std::to_string(8.0 * (i / 10)) + "]\n" +
            "strut_period = 0.6\nstrut_decay = 0.1\n";
  }
  return text + "[[plane]]\n";
}

// A name holding a quote, spaces, `$`, `;`, a newline and non-ASCII letters, and a command a
// shell would run.
const std::string kOddScene = "Bob's $HOME; ball\n\xC4\x82\xC2\xA9;touch PWNED.toml";
const std::string kOddFolder = "out $HOME 'q'; x\n\xC4\x82\xC2\xA9 ;touch PWNED #";

// The tiny scene under kOddScene, its body named with a line break and a gnuplot command.
void writeOddScene() {
  std::string text = readFile(kTiny);
  text.replace(text.find("name = \"ball\""), 13, "name = \"ball\\nsystem('touch PWNED')\\n\"");
  writeFile(kOddScene, text);
  fs::create_directory(kOddFolder);
}

Result run(const std::vector<std::string>& args) {
  Springy springy(args, {});
  return springy.wait(60.0);
}

TEST(Processes, OddNamesReachNoShellInAnyCommand) {
  WorkDir work;
  writeOddScene();
  const std::string out = kOddFolder + "/";
  const std::vector<std::pair<std::vector<std::string>, std::string>> commands = {
      {{"check", kOddScene, "--json", out + "c;touch PWNED.json", "--trace", out + "c $x.csv"}, out + "c $x.csv"},
      {{"render", kOddScene, "-o", out + "v'; touch PWNED.mp4"}, out + "v'; touch PWNED.mp4"},
      {{"frames", kOddScene, "-o", out + "fr $x", "--times", "0,0.5"}, out + "fr $x/" + fs::path(kOddScene).stem().string() + "_t000.50.png"},
      {{"export", kOddScene, "-o", out + "e\n.glb"}, out + "e\n.glb"},
      {{"report", kOddScene, "-o", out + "rep"}, out + "rep/index.html"},
      {{"suggest", kOddScene}, ""},
  };
  for (const auto& [args, output] : commands) {
    const Result r = run(args);
    EXPECT_EQ(r.status, 0) << args[0] << ":\n" << r.output;
    if (!output.empty()) {
      EXPECT_TRUE(fs::is_regular_file(output)) << args[0] << " wrote no " << output;
    }
  }
  EXPECT_TRUE(fs::is_regular_file(out + "c;touch PWNED.json"));
  // A sweep of the scene, run here: its spec (in the folder) names the scene relative to itself.
  writeFile(out + "spec.toml", "scenes = [\"../Bob's $HOME; ball\\n\xC4\x82\xC2\xA9;touch PWNED.toml\"]\n"
                               "[grid]\ndt = [0.005, 0.0025]\n");
  const Result sweep = run({"sweep", out + "spec.toml", "-o", out + "sw"});
  EXPECT_EQ(sweep.status, 0) << sweep.output;
  EXPECT_TRUE(fs::is_regular_file(out + "sw/table.csv")) << sweep.output;
  EXPECT_EQ(filesNamed(work.path(), "PWNED"), std::vector<std::string>{});
}

// sbatch, as a stand-in on PATH that runs the job script at once in its working directory (task 0
// of the array), as Slurm would on a node, and prints a job id.
const char* kFakeSbatch = R"(#!/bin/sh
for script; do :; done
SLURM_ARRAY_TASK_ID=0 sh "$script" >/dev/null 2>&1
echo 4242
)";

TEST(Processes, SlurmSubmissionPassesNoNameToAShell) {
  WorkDir work;
  writeOddScene();
  fs::create_directory("bin");
  writeFile("bin/sbatch", kFakeSbatch);
  fs::permissions("bin/sbatch", fs::perms::owner_all);
  const std::string out = kOddFolder + "/";
  writeFile(out + "spec.toml", "scenes = [\"../Bob's $HOME; ball\\n\xC4\x82\xC2\xA9;touch PWNED.toml\"]\n"
                               "[grid]\ndt = [0.005]\n");
  const char* path = std::getenv("PATH");
  const std::string oldPath = path ? path : "/usr/bin:/bin";
  ::setenv("PATH", ((work.path() / "bin").string() + ":" + oldPath).c_str(), 1);
  const Result r = run({"sweep", out + "spec.toml", "-o", out + "sw", "--slurm"});
  ::setenv("PATH", oldPath.c_str(), 1);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("submitted job array 4242"), std::string::npos) << r.output;
  // The job scripts ran in the sweep's folder: the task's result and the gathered table.
  EXPECT_TRUE(fs::is_regular_file(out + "sw/table.csv")) << r.output;
  EXPECT_TRUE(fs::is_directory(out + "sw/results") && !fs::is_empty(out + "sw/results")) << r.output;
  EXPECT_EQ(filesNamed(work.path(), "PWNED"), std::vector<std::string>{});
}

TEST(Processes, KillingRenderTakesItsChildAlongAndWritesNothingAfter) {
  WorkDir work;
  writeFile("long.toml", longScene());
  fs::create_directory("o");
  writeFile("o/long.mp4", "the video before");
  Springy springy({"render", "long.toml", "-o", "o/long.mp4"}, {});
  // springy-render started, and drawing into its temporary file.
  std::vector<pid_t> children;
  ASSERT_TRUE(within(20.0, [&] {
    children = childrenOf(springy.pid());
    return !children.empty() && std::distance(fs::directory_iterator("o"), fs::directory_iterator()) > 1;
  })) << springy.output();
  ASSERT_EQ(children.size(), 1u);
  const pid_t child = children[0];
  springy.signal(SIGKILL);
  springy.wait();
  EXPECT_TRUE(within(2.0, [&] { return !running(child); })) << "springy-render runs on after springy was killed";
  if (running(child)) ::kill(child, SIGKILL);
  // Nothing written after: the old video as it was, the temporary file gone.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator("o")) files.push_back(e.path().filename().string());
  EXPECT_EQ(files, std::vector<std::string>{"long.mp4"});
  EXPECT_EQ(readFile("o/long.mp4"), "the video before");
}

TEST(Processes, SuggestStopsWithinASecondOfSigterm) {
  WorkDir work;
  writeFile("balls.toml", softBalls(50));
  Springy springy({"suggest", "balls.toml"}, {});
  const auto [r, seconds] = stopAfter(springy, 0.5, SIGTERM);
  EXPECT_EQ(r.status, 143) << r.output;
  EXPECT_LT(seconds, 1.0) << r.output;
}

TEST(Processes, SubstepsAutoSurveyStopsWithinASecondOfCtrlC) {
  Springy springy({"check", kSource + "/scenes/bunny.toml", "--substeps", "auto"}, {});
  const auto [r, seconds] = stopAfter(springy, 1.0, SIGINT);
  EXPECT_NE(r.output.find("surveying the run for --substeps auto"), std::string::npos) << r.output;
  EXPECT_EQ(r.status, 130) << r.output;
  EXPECT_LT(seconds, 1.0) << r.output;
}

TEST(Processes, StudyStopsWithinASecondAndWritesNothing) {
  WorkDir work;
  Springy springy({"study", "accuracy", "--quick", "-o", "st"}, {});
  const auto [r, seconds] = stopAfter(springy, 0.5, SIGTERM);
  EXPECT_EQ(r.status, 143) << r.output;
  EXPECT_LT(seconds, 1.0) << r.output;
  EXPECT_TRUE(!fs::exists("st") || fs::is_empty("st")) << r.output;
}

TEST(Processes, KillingASweepTakesItsTasksAlong) {
  WorkDir work;
  writeFile("long.toml", longScene());
  writeFile("spec.toml", "scenes = [\"long.toml\"]\n[grid]\ndt = [0.0005, 0.00025]\n");
  Springy springy({"sweep", "spec.toml", "-o", "sw", "--jobs", "2"}, {});
  std::vector<pid_t> tasks;
  ASSERT_TRUE(within(20.0, [&] { return (tasks = childrenOf(springy.pid())).size() == 2; })) << springy.output();
  springy.signal(SIGKILL);
  springy.wait();
  for (const pid_t task : tasks) {
    EXPECT_TRUE(within(2.0, [&] { return !running(task); })) << "run-task " << task << " runs on";
    if (running(task)) ::kill(task, SIGKILL);
  }
  // Their results are not written (an interrupted task leaves none).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_TRUE(!fs::exists("sw/results") || fs::is_empty("sw/results"));
}

TEST(Processes, ProgressShowsWithinSecondsWhenAFrameTakesLong) {
  // vbd at 1000 sweeps a step and a step of 10 us: a frame (0.1 s) takes minutes.
  Springy springy({"check", kTiny, "--integrator", "vbd", "--iterations", "1000", "--dt", "1e-5"}, {});
  const bool shown = within(4.0, [&] { return springy.output().find("0/10 frames") != std::string::npos; });
  const auto [r, seconds] = stopAfter(springy, 0.0, SIGTERM);
  EXPECT_TRUE(shown) << r.output;
  EXPECT_EQ(r.status, 143) << r.output;
  EXPECT_LT(seconds, 1.0) << r.output;
}

}  // namespace

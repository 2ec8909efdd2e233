// `springy sweep`, `run-task`, `gather` and `check --json/--junit` as a user runs them: the same
// spec gives the same manifest and table, bad specs name their file, line and key, a killed sweep
// resumes with only its unfinished tasks, run-task finds its index where schedulers put it, GNU
// parallel runs a manifest to the same table, and a JUnit file passes a real consumer's checks.
// (The Slurm cluster test is tests/slurm_sweep.sh.)
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "run_springy.h"

extern char** environ;

namespace springy {
namespace {

namespace fs = std::filesystem;
using test::runSpringy;

const std::string kSphere = std::string(SPRINGY_SOURCE_DIR) + "/scenes/single_sphere.toml";

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A fresh directory per test, removed after it.
class SweepTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/springy-sweep-test.XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  // A spec over single_sphere: dt x drag, `duration` s each.
  fs::path gridSpec(const std::string& name, double duration, const std::string& extra = "") {
    const fs::path spec = dir_ / name;
    writeFile(spec, "scenes = [\"" + kSphere + "\"]\n" + extra + "[set]\nduration = " + std::to_string(duration) +
                        "\n[grid]\ndt = [0.002, 0.004]\nenvironment.drag = [0.1, 0.2]\n");
    return spec;
  }
  fs::path dir_;
};

// The tests name every path absolutely, quoted for the shell.
std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// A shell command line; its status and output (stdout and stderr).
test::CommandResult shell(const std::string& command) {
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen((command + " 2>&1").c_str(), "r"), pclose);
  test::CommandResult r{-1, ""};
  char buffer[4096];
  while (fgets(buffer, sizeof buffer, pipe.get())) r.output += buffer;
  const int raw = pclose(pipe.release());
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

const std::string kSpringy = SPRINGY_BINARY;
const std::string kJunitCheck = "python3 '" + std::string(SPRINGY_SOURCE_DIR) + "/tests/junit_check.py' ";

int lineCount(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

TEST_F(SweepTest, SameSpecGivesByteIdenticalManifestsAndTables) {
  const fs::path spec = gridSpec("grid.toml", 0.3);
  const auto a = runSpringy("sweep " + q(spec) + " -o " + q(dir_ / "a"));
  ASSERT_EQ(a.status, 0) << a.output;
  // One task at a time: another completion order, the same table.
  const auto b = runSpringy("sweep " + q(spec) + " -o " + q(dir_ / "b") + " --jobs 1");
  ASSERT_EQ(b.status, 0) << b.output;
  for (const char* file : {"manifest.jsonl", "table.csv", "table.json", "map-single_sphere.png"}) {
    const std::string first = readFile(dir_ / "a" / file);
    EXPECT_FALSE(first.empty()) << file;
    EXPECT_EQ(first, readFile(dir_ / "b" / file)) << file;
  }
  // The grid in the spec's order, the first key outermost; each task a springy command line.
  const std::string manifest = readFile(dir_ / "a" / "manifest.jsonl");
  ASSERT_EQ(lineCount(manifest), 4);
  std::istringstream lines(manifest);
  std::string line;
  std::vector<nlohmann::json> tasks;
  while (std::getline(lines, line)) tasks.push_back(nlohmann::json::parse(line));
  EXPECT_EQ(tasks[1]["task"], 1);
  EXPECT_EQ(tasks[1]["point"]["dt"], 0.002);
  EXPECT_EQ(tasks[1]["point"]["environment.drag"], 0.2);
  EXPECT_EQ(tasks[2]["point"]["dt"], 0.004);
  const std::vector<std::string> command = tasks[1]["command"];
  const std::vector<std::string> expected = {"check", "--duration",          "0.3", "--dt", "0.002",
                                             "--set", "environment.drag=0.2"};
  ASSERT_EQ(command.size(), expected.size() + 1);
  EXPECT_EQ(command[0], "check");
  EXPECT_EQ(std::vector<std::string>(command.begin() + 2, command.end()),
            std::vector<std::string>(expected.begin() + 1, expected.end()));
  EXPECT_EQ(tasks[1]["outputs"]["result"], "results/0001.json");
  // The table: one row per task and body, the results of the task's own settings.
  const std::string table = readFile(dir_ / "a" / "table.csv");
  EXPECT_EQ(lineCount(table), 5) << table;
  EXPECT_NE(table.find(",0.002,0.2,ok,ball,150,"), std::string::npos) << table;  // 0.3 s at 2 ms: 150 steps
  EXPECT_NE(table.find(",0.004,0.1,ok,ball,75,"), std::string::npos) << table;
}

TEST_F(SweepTest, DragSetByTheGridChangesTheResultAsTheSceneKeyWould) {
  // The point's --set is the scene key: the same as a scene file with that drag.
  std::string scene = readFile(kSphere);
  const std::string from = "drag = 0.15", to = "drag = 0.4";
  ASSERT_NE(scene.find(from), std::string::npos);
  scene.replace(scene.find(from), from.size(), to);
  writeFile(dir_ / "drag.toml", scene);
  const auto edited = runSpringy("check " + q(dir_ / "drag.toml") + " --duration 0.3 --json " + q(dir_ / "e.json"));
  ASSERT_EQ(edited.status, 0) << edited.output;
  const auto set = runSpringy("check " + q(dir_ / "drag.toml") + " --duration 0.3 --set environment.drag=0.4 " +
                              "--set body.mass=8.0 --json " + q(dir_ / "s.json"));
  ASSERT_EQ(set.status, 0) << set.output;
  const auto plain = runSpringy("check " + q(kSphere) + " --duration 0.3 --json " + q(dir_ / "p.json"));
  ASSERT_EQ(plain.status, 0) << plain.output;
  auto bodies = [&](const char* file) { return nlohmann::json::parse(readFile(dir_ / file))["scenes"][0]["bodies"]; };
  EXPECT_EQ(bodies("e.json"), bodies("s.json"));
  EXPECT_NE(bodies("e.json"), bodies("p.json"));  // drag matters: not a vacuous match
}

TEST_F(SweepTest, BadSpecsNameFileLineAndKey) {
  struct Case {
    std::string spec, expected;
  };
  const std::string scenes = "scenes = [\"" + kSphere + "\"]\n";
  const std::vector<Case> cases = {
      {scenes + "[grid]\ndt = [0.002, -1]\n", "bad.toml:3:14: key 'dt' = -1"},
      {scenes + "[grid]\nenvironment.drag = [0.1, -2]\n", "bad.toml:3:26: key 'environment.drag' = -2"},
      {scenes + "[set]\nbody.mass = 2.0\n[grid]\nenvironment.drag = [-2]\n",
       "bad.toml:5:21: key 'environment.drag' = -2"},
      {scenes + "[grid]\nenvironment.dragg = [0.1]\n", "bad.toml:3:22: key 'environment.dragg' = 0.1"},
      {scenes + "[set]\nbody.3.mass = 1.0\n", "bad.toml:3:15: key 'body.3.mass' = 1.0"},
      {scenes + "colour = 1\n", "bad.toml:2:10: unknown key 'colour'"},
      {scenes + "command = \"draw\"\n", "bad.toml:2:11: key 'command'"},
      {scenes + "args = [\"--min-volume\", \"2\"]\n", "bad.toml:2:8: key 'args'"},
      {scenes + "[grid]\ndt = []\n", "bad.toml:3:6: [grid] key 'dt': expected a non-empty array"},
      {scenes + "[grid]\nintegrator = [4]\n", "bad.toml:3:15: [grid] key 'integrator': expected a string"},
      {scenes + "[grid]\ndrag = [1]\n", "bad.toml:3:9: [grid] key 'drag': not a command-line setting"},
      {"scenes = [\"nowhere.toml\"]\n", "bad.toml:1:11: key 'scenes': nowhere.toml: no such scene file"},
      {scenes + "[grid]\ndt = [0.002\n", "bad.toml:3:"},
  };
  for (const Case& c : cases) {
    writeFile(dir_ / "bad.toml", c.spec);
    fs::remove_all(dir_ / "out");
    const auto r = runSpringy("sweep " + q(dir_ / "bad.toml") + " -o " + q(dir_ / "out"));
    EXPECT_EQ(r.status, 1) << c.spec << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.spec << "\n" << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "out" / "manifest.jsonl")) << c.spec;  // nothing runs
  }
}

// posix_spawn of springy with its output in `log`.
pid_t startSpringy(const std::vector<std::string>& args, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<std::string> all = {SPRINGY_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  posix_spawn(&pid, SPRINGY_BINARY, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

int resultCount(const fs::path& dir) {
  int n = 0;
  if (!fs::exists(dir / "results")) return 0;
  for (const auto& e : fs::directory_iterator(dir / "results")) {
    n += e.path().filename().string().front() != '.' ? 1 : 0;  // not a result being written
  }
  return n;
}

TEST_F(SweepTest, KilledSweepResumesWithOnlyItsUnfinishedTasks) {
  // Eight tasks of about a tenth of a second each, one at a time.
  const fs::path spec = dir_ / "resume.toml";
  writeFile(spec, "scenes = [\"" + kSphere + "\"]\n[set]\nduration = 2.0\n[grid]\ndt = [0.002, 0.004]\n" +
                      "environment.drag = [0.1, 0.2, 0.3, 0.4]\n");
  const fs::path out = dir_ / "resume";
  const pid_t pid = startSpringy({"sweep", spec.string(), "-o", out.string(), "--jobs", "1"}, dir_ / "first.log");
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (resultCount(out) < 2 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, SIGTERM);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 143) << readFile(dir_ / "first.log");
  const int finished = resultCount(out);
  ASSERT_GE(finished, 2);
  ASSERT_LT(finished, 8) << "the sweep finished before it was killed; make its tasks longer";
  EXPECT_FALSE(fs::exists(out / "table.csv"));
  // The finished tasks' results and logs, to see that the rerun leaves them alone.
  std::map<std::string, std::pair<std::string, std::uintmax_t>> before;
  for (const auto& e : fs::directory_iterator(out / "results")) {
    if (e.path().filename().string().front() == '.') continue;
    const std::string task = e.path().stem().string();
    before[task] = {readFile(e.path()), fs::file_size(out / "logs" / (task + ".log"))};
  }

  const auto rerun = runSpringy("sweep " + q(spec) + " -o " + q(out) + " --jobs 1");
  ASSERT_EQ(rerun.status, 0) << rerun.output;
  const std::string expected = "sweep: 8 tasks, " + std::to_string(finished) + " finished already, running " +
                               std::to_string(8 - finished) + ":";
  EXPECT_NE(rerun.output.find(expected), std::string::npos) << rerun.output;
  // Progress lines only for the tasks it ran, in task order.
  EXPECT_EQ(static_cast<int>(std::count(rerun.output.begin(), rerun.output.end(), '[')), 8 - finished) << rerun.output;
  for (const auto& [task, old] : before) {
    EXPECT_EQ(readFile(out / "results" / (task + ".json")), old.first) << task;
    EXPECT_EQ(fs::file_size(out / "logs" / (task + ".log")), old.second) << task << ": run again";
  }
  // The same table as a sweep that was never interrupted.
  const auto clean = runSpringy("sweep " + q(spec) + " -o " + q(dir_ / "clean"));
  ASSERT_EQ(clean.status, 0) << clean.output;
  EXPECT_EQ(readFile(out / "table.csv"), readFile(dir_ / "clean" / "table.csv"));
  EXPECT_EQ(readFile(out / "table.json"), readFile(dir_ / "clean" / "table.json"));
  // A third run has nothing to do.
  const auto again = runSpringy("sweep " + q(spec) + " -o " + q(out));
  EXPECT_NE(again.output.find("8 finished already, running 0"), std::string::npos) << again.output;
}

TEST_F(SweepTest, RunTaskTakesItsIndexFromTheScheduler) {
  const fs::path spec = gridSpec("grid.toml", 0.2);
  const fs::path out = dir_ / "m";
  const auto made = runSpringy("sweep " + q(spec) + " -o " + q(out) + " --manifest-only");
  ASSERT_EQ(made.status, 0) << made.output;
  ASSERT_EQ(resultCount(out), 0);
  const std::string manifest = q(out / "manifest.jsonl");
  struct Case {
    std::string env, result;
  };
  // Slurm's array index and Kubernetes' completion index count from 0, GNU parallel's sequence from 1.
  const std::string unset = "env -u SLURM_ARRAY_TASK_ID -u JOB_COMPLETION_INDEX -u PARALLEL_SEQ ";
  const auto none = shell(unset + kSpringy + " run-task " + manifest);
  EXPECT_EQ(none.status, 1);
  EXPECT_NE(none.output.find("no --index, and none of SLURM_ARRAY_TASK_ID"), std::string::npos) << none.output;
  for (const Case& c : std::vector<Case>{
           {"SLURM_ARRAY_TASK_ID=2", "0002"}, {"JOB_COMPLETION_INDEX=3", "0003"}, {"PARALLEL_SEQ=1", "0000"}}) {
    const auto ran = shell(unset + c.env + " " + kSpringy + " run-task " + manifest + " --threads 1");
    EXPECT_EQ(ran.status, 0) << ran.output;
    EXPECT_TRUE(fs::exists(out / "results" / (c.result + ".json"))) << c.env << ran.output;
  }
  EXPECT_EQ(resultCount(out), 3);
  const auto again = runSpringy("run-task " + manifest + " --index 2");
  EXPECT_EQ(again.status, 0);
  EXPECT_NE(again.output.find("task 2: finished already"), std::string::npos) << again.output;
  const auto missing = runSpringy("gather " + manifest);
  EXPECT_EQ(missing.status, 1);  // task 1 has no result
  EXPECT_NE(missing.output.find("1 missing"), std::string::npos) << missing.output;
  EXPECT_NE(readFile(out / "table.csv").find("\n1,"), std::string::npos);
  EXPECT_NE(readFile(out / "table.csv").find(",missing,"), std::string::npos);
  const auto beyond = runSpringy("run-task " + manifest + " --index 4");
  EXPECT_EQ(beyond.status, 1);
  EXPECT_NE(beyond.output.find("no task 4 (it has 4, from 0)"), std::string::npos) << beyond.output;
}

TEST_F(SweepTest, FailedTaskKeepsItsErrorInItsResult) {
  // Not at rest after 0.5 s: every point fails the check, and says why.
  const fs::path spec = gridSpec("fail.toml", 0.5, "args = [\"--end-at-rest\"]\n");
  const auto r = runSpringy("sweep " + q(spec) + " -o " + q(dir_ / "f"));
  EXPECT_EQ(r.status, 0) << r.output;  // every task ran and recorded its result
  const auto result = nlohmann::json::parse(readFile(dir_ / "f" / "results" / "0000.json"));
  EXPECT_EQ(result["status"], "failed");
  EXPECT_NE(result["message"].get<std::string>().find("body 'ball' is not at rest at the end"), std::string::npos);
  EXPECT_EQ(result["records"][0]["failed_body"], "ball");
  EXPECT_NE(readFile(dir_ / "f" / "table.csv").find(",failed,ball,"), std::string::npos);
  EXPECT_NE(r.output.find("0 ok, 4 failed"), std::string::npos) << r.output;
}

TEST_F(SweepTest, LocalRunnerKeepsThreadsWithinTheCores) {
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const fs::path spec = gridSpec("grid.toml", 0.2);
  const auto r = runSpringy("sweep " + q(spec) + " -o " + q(dir_ / "t"));
  ASSERT_EQ(r.status, 0) << r.output;
  const unsigned slots = std::min(cores, 4u), each = std::max(1u, cores / slots);
  EXPECT_NE(r.output.find(std::to_string(slots) + " at a time, " + std::to_string(each) + " thread"), std::string::npos)
      << r.output;
  EXPECT_LE(slots * each, cores);
  EXPECT_NE(readFile(dir_ / "t" / "logs" / "0000.log").find("--threads " + std::to_string(each)), std::string::npos);
  // A task's own threads are its own.
  const fs::path own = gridSpec("own.toml", 0.2, "");
  writeFile(own, readFile(own) + "threads = [1]\n");
  const auto o = runSpringy("sweep " + q(own) + " -o " + q(dir_ / "o"));
  ASSERT_EQ(o.status, 0) << o.output;
  EXPECT_NE(readFile(dir_ / "o" / "logs" / "0000.log").find("threads: 1"), std::string::npos);
}

TEST_F(SweepTest, GnuParallelRunsTheManifestToTheSameTable) {
  const fs::path spec = gridSpec("grid.toml", 0.2);
  const auto local = runSpringy("sweep " + q(spec) + " -o " + q(dir_ / "local"));
  ASSERT_EQ(local.status, 0) << local.output;
  const fs::path out = dir_ / "parallel";
  ASSERT_EQ(runSpringy("sweep " + q(spec) + " -o " + q(out) + " --manifest-only").status, 0);
  // The README's example: one task per job slot, the index from PARALLEL_SEQ.
  const auto p = shell("parallel --will-cite -j 2 -N0 " + kSpringy + " run-task " + q(out / "manifest.jsonl") +
                       " --threads 1 ::: 1 2 3 4");
  ASSERT_EQ(p.status, 0) << p.output;
  const auto g = runSpringy("gather " + q(out / "manifest.jsonl"));
  ASSERT_EQ(g.status, 0) << g.output;
  EXPECT_EQ(readFile(out / "table.csv"), readFile(dir_ / "local" / "table.csv"));
  EXPECT_EQ(readFile(out / "table.json"), readFile(dir_ / "local" / "table.json"));
}

TEST_F(SweepTest, CheckJunitPassesAJunitConsumer) {
  // Three scenes: one passes (nothing pulls the ball: at rest), one fails (it falls), one has an error.
  const std::string body =
      "[[body]]\nname = \"ball\"\nshape = \"octahedron_sphere\"\nsubdivisions = 2\nradius = 1.0\n"
      "position = [0.0, 3.0, 0.0]\nmass = 1.0\n\n[[plane]]\n";
  writeFile(dir_ / "still.toml",
            "[scene]\nduration = 1.2\ndt = 0.002\n[environment]\ngravity = [0.0, 0.0, 0.0]\n" + body);
  writeFile(dir_ / "falls.toml", "[scene]\nduration = 1.2\ndt = 0.002\n" + body);
  writeFile(dir_ / "broken.toml", "[scene]\nduraton = 1.2\n" + body);
  const fs::path xml = dir_ / "check.xml", json = dir_ / "check.json";
  const auto r = runSpringy("check " + q(dir_ / "still.toml") + " " + q(dir_ / "falls.toml") + " " +
                            q(dir_ / "broken.toml") + " --end-at-rest --junit " + q(xml) + " --json " + q(json));
  EXPECT_EQ(r.status, 1) << r.output;
  // The failure's message as check prints it.
  const std::size_t at = r.output.find("FAILED: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string message = r.output.substr(at + 8, r.output.find('\n', at) - at - 8);
  writeFile(dir_ / "message", message);
  const auto checked = shell(kJunitCheck + q(xml) + " --tests 3 --failures 1 --errors 1 --failure-message \"$(cat " +
                             q(dir_ / "message") + ")\"");
  EXPECT_EQ(checked.status, 0) << checked.output << readFile(xml);
  // Wrong expectations fail: the consumer checks, it does not just parse.
  const auto wrong = shell(kJunitCheck + q(xml) + " --tests 3 --failures 0 --errors 1");
  EXPECT_NE(wrong.status, 0) << wrong.output;
  // --json: the same records as data.
  const auto data = nlohmann::json::parse(readFile(json))["scenes"];
  ASSERT_EQ(data.size(), 3u);
  EXPECT_EQ(data[0]["status"], "ok");
  EXPECT_EQ(data[0]["bodies"][0]["at_rest"], true);
  EXPECT_EQ(data[1]["status"], "failed");
  EXPECT_EQ(data[1]["message"], message);
  EXPECT_EQ(data[2]["status"], "error");
  EXPECT_NE(data[2]["message"].get<std::string>().find("broken.toml:2:1"), std::string::npos) << data[2];
}

// A sweep's folder holds files of names it writes (table.csv, ...) only as springy wrote them (the
// folder's record): a user's table there stops the sweep before it plans anything, the file kept.
TEST_F(SweepTest, AUsersTableInTheFolderStopsTheSweepBeforeItPlans) {
  const fs::path spec = gridSpec("grid.toml", 0.3);
  fs::create_directories(dir_ / "out");
  writeFile(dir_ / "out" / "table.csv", "my table");
  const auto r = runSpringy("sweep " + q(spec) + " -o " + q(dir_ / "out"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("that springy did not write"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(": table.csv;"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "manifest.jsonl"));
  std::ifstream in(dir_ / "out" / "table.csv");
  std::string kept;
  std::getline(in, kept);
  EXPECT_EQ(kept, "my table");
}

}  // namespace
}  // namespace springy

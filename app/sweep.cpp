// `springy sweep SPEC.toml`: a spec (docs/sweeps.md) names scenes, settings over a grid or a list of
// points, and the command per point; sweep turns it into a manifest, one task per line
// (app/sweep.h), checks every task before any runs, and runs the tasks here (a local runner: one
// task per core) or submits them to Slurm as a job array with a gather job after it.
// `springy run-task MANIFEST`: runs one task and writes its result.
#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <toml++/toml.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "app/atomic_file.h"
#include "app/child.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/sweep.h"
#include "run/load.h"
#include "sim/error.h"
#include "sim/limits.h"

extern char** environ;

namespace springy {
namespace {

namespace fs = std::filesystem;

constexpr std::uintmax_t kMaxManifestBytes = 256u << 20;
constexpr std::uintmax_t kMaxResultBytes = 64u << 20;

// ---------------------------------------------------------------------------------------------
// The spec.

// The command-line settings a point may set; every other key is a scene key (TABLE.KEY).
constexpr const char* kSettings[] = {"integrator", "dt", "substeps", "duration", "threads"};

bool isSetting(const std::string& key) {
  return std::find_if(std::begin(kSettings), std::end(kSettings), [&](const char* s) { return key == s; }) !=
         std::end(kSettings);
}

struct SpecValue {
  std::string key;  // dotted
  const toml::node* node = nullptr;
};

struct Axis {
  std::string key;
  const toml::node* node = nullptr;  // the array of values
  std::vector<const toml::node*> values;
};

struct Spec {
  std::string path;
  toml::table root;
  std::vector<std::string> scenes;  // as written (relative to the spec's directory)
  const toml::node* scenesNode = nullptr;
  std::string command = "check";
  std::vector<std::string> args;
  const toml::node* argsNode = nullptr;
  std::vector<SpecValue> fixed;              // [set]
  std::vector<Axis> grid;                    // [grid]
  std::vector<std::vector<SpecValue>> list;  // [[point]]
};

std::string where(const std::string& path, const toml::node& node) {
  const toml::source_position at = node.source().begin;
  return path + ":" + std::to_string(at.line) + ":" + std::to_string(at.column);
}

[[noreturn]] void fail(const Spec& spec, const toml::node& node, const std::string& message) {
  throw Error(where(spec.path, node) + ": " + message);
}

bool before(const toml::node* a, const toml::node* b) {
  const toml::source_position pa = a->source().begin, pb = b->source().begin;
  return pa.line != pb.line ? pa.line < pb.line : pa.column < pb.column;
}

// The table's leaves as dotted keys, in the order they are written (toml++ keeps keys sorted).
void flatten(const toml::table& table, const std::string& prefix, std::vector<SpecValue>& out) {
  for (const auto& [key, node] : table) {
    const std::string name = prefix + std::string(key.str());
    if (const toml::table* sub = node.as_table()) {
      flatten(*sub, name + ".", out);
    } else {
      out.push_back({name, &node});
    }
  }
}

std::vector<SpecValue> flattened(const toml::table& table) {
  std::vector<SpecValue> out;
  flatten(table, "", out);
  std::stable_sort(out.begin(), out.end(),
                   [](const SpecValue& a, const SpecValue& b) { return before(a.node, b.node); });
  return out;
}

// A value a key may take: a number, a string, a boolean, or an array of them (a vector).
bool isPlainValue(const toml::node& node) {
  if (const toml::array* a = node.as_array()) {
    return std::all_of(a->begin(), a->end(), [](const toml::node& n) { return isPlainValue(n) && !n.is_array(); });
  }
  return node.is_number() || node.is_string() || node.is_boolean();
}

void checkKey(const Spec& spec, const std::string& section, const SpecValue& v) {
  const std::string what = section + " key '" + v.key + "'";
  if (!isPlainValue(*v.node))
    fail(spec, *v.node, what + ": expected a number, a string, true or false, or an array of them");
  if (isSetting(v.key)) {
    const bool ok = v.key == "integrator" ? v.node->is_string()
                    : v.key == "substeps" ? v.node->is_integer() || v.node->value<std::string>() == "auto"
                    : v.key == "threads"  ? v.node->is_integer()
                                          : v.node->is_number();
    if (!ok) {
      fail(spec, *v.node,
           what + ": expected " +
               (v.key == "integrator" ? "a string (" + integratorNames() + ")"
                : v.key == "substeps" ? std::string("a whole number or \"auto\"")
                : v.key == "threads"  ? std::string("a whole number")
                                      : std::string("a number of seconds")));
    }
  } else if (v.key.find('.') == std::string::npos) {
    fail(spec, *v.node,
         what +
             ": not a command-line setting (integrator, dt, substeps, duration, threads) nor a scene key "
             "(TABLE.KEY, e.g. environment.drag, body.mass, body.0.mass)");
  }
}

std::vector<std::string> stringList(const Spec& spec, const toml::node& node, const std::string& key) {
  const toml::array* array = node.as_array();
  std::vector<std::string> out;
  if (array) {
    for (const toml::node& n : *array) {
      if (!n.is_string()) fail(spec, n, "key '" + key + "': expected strings");
      out.push_back(n.as_string()->get());
    }
  }
  if (!array) fail(spec, node, "key '" + key + "': expected an array of strings");
  return out;
}

Spec readSpec(const std::string& path) {
  Spec spec;
  spec.path = path;
  checkInputFile(path, kMaxSceneFileBytes, "sweep spec");
  try {
    spec.root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    const toml::source_position at = e.source().begin;
    throw Error(path + ":" + std::to_string(at.line) + ":" + std::to_string(at.column) + ": " +
                std::string(e.description()));
  }
  for (const auto& [key, node] : spec.root) {
    const std::string k(key.str());
    if (k == "scenes") {
      spec.scenes = stringList(spec, node, k);
      spec.scenesNode = &node;
      if (spec.scenes.empty()) fail(spec, node, "key 'scenes': name at least one scene file");
    } else if (k == "command") {
      const std::optional<std::string> c = node.value<std::string>();
      if (!c || (*c != "check" && *c != "render" && *c != "frames")) {
        fail(spec, node, "key 'command': expected \"check\", \"render\" or \"frames\"");
      }
      spec.command = *c;
    } else if (k == "args") {
      spec.args = stringList(spec, node, k);
      spec.argsNode = &node;
    } else if (k == "set" || k == "grid") {
      if (!node.is_table()) fail(spec, node, "'" + k + "' must be a table ([" + k + "])");
      for (SpecValue& v : flattened(*node.as_table())) {
        if (k == "set") {
          checkKey(spec, "[set]", v);
          spec.fixed.push_back(v);
          continue;
        }
        const toml::array* values = v.node->as_array();
        if (!values || values->empty())
          fail(spec, *v.node, "[grid] key '" + v.key + "': expected a non-empty array of values");
        Axis axis{v.key, v.node, {}};
        for (const toml::node& value : *values) {
          checkKey(spec, "[grid]", {v.key, &value});
          axis.values.push_back(&value);
        }
        spec.grid.push_back(std::move(axis));
      }
    } else if (k == "point") {
      const toml::array* points = node.as_array();
      if (!points || !points->is_array_of_tables()) fail(spec, node, "'point' must be an array of tables ([[point]])");
      for (const toml::node& p : *points) {
        std::vector<SpecValue> values = flattened(*p.as_table());
        for (const SpecValue& v : values) checkKey(spec, "[[point]]", v);
        spec.list.push_back(std::move(values));
      }
    } else {
      fail(spec, node, "unknown key '" + k + "' (expected scenes, command, args, [set], [grid] or [[point]])");
    }
  }
  if (!spec.scenesNode) throw Error(path + ": no 'scenes' (the scene files to run, relative to the spec)");
  if (!spec.grid.empty() && !spec.list.empty()) {
    fail(spec, *spec.list.front().front().node, "give either [grid] or [[point]], not both");
  }
  const auto checkFixed = [&](const SpecValue& v) {
    for (const SpecValue& f : spec.fixed) {
      if (f.key == v.key) fail(spec, *v.node, "key '" + v.key + "' is also in [set]");
    }
  };
  for (const Axis& a : spec.grid) checkFixed({a.key, a.node});
  for (const auto& point : spec.list) std::for_each(point.begin(), point.end(), checkFixed);
  return spec;
}

// A TOML value as text that reads back the same (floats with every digit, always as floats).
std::string tomlText(const toml::node& node) {
  if (const toml::array* a = node.as_array()) {
    std::string out = "[";
    for (std::size_t i = 0; i < a->size(); ++i) out += (i ? ", " : "") + tomlText(*a->get(i));
    return out + "]";
  }
  if (node.is_string()) return Json(node.as_string()->get()).dump();  // a JSON string is a TOML basic string
  if (node.is_boolean()) return node.as_boolean()->get() ? "true" : "false";
  if (node.is_integer()) return std::to_string(node.as_integer()->get());
  std::string text = exactNumber(node.as_floating_point()->get());
  if (text.find_first_of(".eni") == std::string::npos) text += ".0";
  return text;
}

Json jsonOf(const toml::node& node) {
  if (const toml::array* a = node.as_array()) {
    Json out = Json::array();
    for (const toml::node& n : *a) out.push_back(jsonOf(n));
    return out;
  }
  if (node.is_string()) return node.as_string()->get();
  if (node.is_boolean()) return node.as_boolean()->get();
  if (node.is_integer()) return node.as_integer()->get();
  const double v = node.as_floating_point()->get();
  return std::isfinite(v) ? Json(v) : Json(exactNumber(v));
}

// The setting's command-line text: "rk4", "0.002", "8".
std::string settingText(const toml::node& node) {
  return node.is_string()    ? node.as_string()->get()
         : node.is_integer() ? tomlText(node)
                             : exactNumber(node.as_floating_point()->get());
}

// ---------------------------------------------------------------------------------------------
// Tasks.

struct PlannedTask {
  SweepTask task;
  std::vector<SpecValue> values;  // the point's, for errors
};

std::string taskName(long index, const char* pattern) {
  char name[64];
  std::snprintf(name, sizeof name, pattern, index);
  return name;
}

std::vector<PlannedTask> planTasks(const Spec& spec, const std::vector<std::string>& scenes) {
  std::vector<std::vector<SpecValue>> points;
  if (!spec.list.empty()) {
    points = spec.list;
  } else {
    points.emplace_back();
    for (const Axis& axis : spec.grid) {  // the first key outermost: the order the spec reads
      std::vector<std::vector<SpecValue>> next;
      for (const auto& point : points) {
        for (const toml::node* value : axis.values) {
          next.push_back(point);
          next.back().push_back({axis.key, value});
        }
      }
      points = std::move(next);
    }
  }
  std::vector<PlannedTask> tasks;
  for (const std::string& scene : scenes) {
    for (const auto& own : points) {
      std::vector<SpecValue> values = spec.fixed;
      values.insert(values.end(), own.begin(), own.end());
      PlannedTask p;
      SweepTask& t = p.task;
      t.index = static_cast<long>(tasks.size());
      t.scene = scene;
      t.point = Json::object();
      t.command = {spec.command, scene};
      for (const SpecValue& v : values) {
        t.point[v.key] = jsonOf(*v.node);
        if (isSetting(v.key)) {
          t.command.insert(t.command.end(), {"--" + v.key, settingText(*v.node)});
        } else {
          t.command.insert(t.command.end(), {"--set", v.key + "=" + tomlText(*v.node)});
        }
      }
      t.command.insert(t.command.end(), spec.args.begin(), spec.args.end());
      t.result = taskName(t.index, "results/%04ld.json");
      t.log = taskName(t.index, "logs/%04ld.log");
      if (spec.command != "check") {
        t.directory = taskName(t.index, "outputs/%04ld/");
        t.command.insert(t.command.end(), {"-o", t.directory});
      }
      p.values = std::move(values);
      tasks.push_back(std::move(p));
    }
  }
  return tasks;
}

// The point's key that an error message names, or null: the scene key the scene reader refused
// ("key 'drag'"), else the option ("--dt", "--set body.3.mass=1: ...").
const SpecValue* named(const std::vector<SpecValue>& values, const std::string& message) {
  for (const SpecValue& v : values) {
    if (!isSetting(v.key) && message.find("key '" + v.key.substr(v.key.rfind('.') + 1) + "'") != std::string::npos) {
      return &v;
    }
  }
  for (const SpecValue& v : values) {
    if (message.find(isSetting(v.key) ? "--" + v.key : "--set " + v.key + "=") != std::string::npos) return &v;
  }
  return nullptr;
}

// Parses each task's command and reads its scene with its settings, as run-task will: a bad key
// or value fails here, naming the spec's line, before anything runs.
void validateTasks(const Spec& spec, const std::vector<PlannedTask>& tasks) {
  for (const PlannedTask& p : tasks) {
    std::string message;
    bool parseError = false;
    CommandLine cli;
    try {
      parseCommandLine(cli, p.task.command);
      const RunOptions& overrides = spec.command == "check"    ? cli.check.run
                                      : spec.command == "render" ? cli.render.run
                                                                 : cli.frames.run;
      loadSceneWith(p.task.scene, overrides, /*advise=*/false);
      continue;
    } catch (const CLI::ParseError& e) {
      message = e.what();
      parseError = true;
    } catch (const Error& e) {
      message = e.what();
    }
    std::string point;
    for (const SpecValue& v : p.values) point += (point.empty() ? "" : ", ") + v.key + " = " + tomlText(*v.node);
    const std::string task = "task " + std::to_string(p.task.index) + " (" + p.task.scene +
                             (point.empty() ? "" : ", " + point) + "): " + message;
    // The scene file's own error (its line given): the scene, not the point.
    const bool sceneOwn = message.rfind(p.task.scene + ":", 0) == 0 && message.size() > p.task.scene.size() + 1 &&
                          std::isdigit(static_cast<unsigned char>(message[p.task.scene.size() + 1]));
    const std::size_t sceneIndex =
        static_cast<std::size_t>(p.task.index) / std::max<std::size_t>(1, tasks.size() / spec.scenes.size());
    const toml::node& sceneNode = *spec.scenesNode->as_array()->get(std::min(sceneIndex, spec.scenes.size() - 1));
    if (sceneOwn) fail(spec, sceneNode, "key 'scenes': " + task);
    if (const SpecValue* v = named(p.values, message)) {
      fail(spec, *v->node, "key '" + v->key + "' = " + tomlText(*v->node) + ": " + task);
    }
    if (spec.argsNode && (parseError || p.values.empty())) fail(spec, *spec.argsNode, "key 'args': " + task);
    if (!p.values.empty()) {
      const SpecValue& v = p.values.front();
      fail(spec, *v.node, "key '" + v.key + "' = " + tomlText(*v.node) + ": " + task);
    }
    fail(spec, sceneNode, "key 'scenes': " + task);
  }
}

std::string manifestLine(const SweepTask& t) {
  Json line;
  line["task"] = t.index;
  line["scene"] = t.scene;
  line["point"] = t.point;
  line["command"] = t.command;
  line["outputs"] = {{"result", t.result}, {"log", t.log}};
  if (!t.directory.empty()) line["outputs"]["directory"] = t.directory;
  return line.dump() + "\n";
}

// ---------------------------------------------------------------------------------------------
// Running.


// The cores this process may run on (its affinity mask: taskset, a cgroup's cpuset).
unsigned usableCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

// The --threads a task's command sets, or 0.
unsigned ownThreads(const SweepTask& task) {
  const auto it = std::find(task.command.begin(), task.command.end(), "--threads");
  if (it == task.command.end() || it + 1 == task.command.end()) return 0;
  return static_cast<unsigned>(std::strtoul((it + 1)->c_str(), nullptr, 10));
}

std::string describe(const SweepTask& t) {
  std::string text = t.scene;
  for (const auto& [key, value] : t.point.items()) {
    text += " " + key + "=" + (value.is_string() ? value.get<std::string>() : value.dump());
  }
  return text;
}

pid_t spawnTask(const std::string& exe, const SweepTask& task, unsigned threads) {
  makeDirectories(fs::path(task.log).parent_path().string(), "logs");
  const int log = ::open(task.log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
  if (log < 0) throw Error("cannot open the task's log '" + task.log + "': " + errorText(errno));
  std::vector<std::string> args = {"run-task", "manifest.jsonl", "--index", std::to_string(task.index)};
  if (threads > 0) args.insert(args.end(), {"--threads", std::to_string(threads)});
  try {
    const pid_t pid = startChild(exe, args, "", log);
    ::close(log);
    return pid;
  } catch (...) {
    ::close(log);
    throw;
  }
}

// A task's run-task child: its task, the threads it holds and when it started.
struct RunningTask {
  const SweepTask* task;
  unsigned threads;
  std::chrono::steady_clock::time_point start;
};

// The local runner's state (runLocally): the unfinished tasks, `slots` at a time with `threadsEach`
// threads each, the children running, and the progress lines not yet printed.
class LocalRunner {
 public:
  LocalRunner(const std::vector<SweepTask>& tasks, unsigned jobs);
  LocalRunner(const LocalRunner&) = delete;
  LocalRunner& operator=(const LocalRunner&) = delete;

  // Runs the unfinished tasks and gathers the results; returns the exit status.
  int run();

 private:
  // Starts pending tasks while a slot is free and the cores have room for their threads.
  void startTasks();
  // After an interruption: stops the children, waits for them and says how to resume; returns the exit status.
  int stop();
  // Takes a child that ended: its task's progress line, printed when the tasks before it are.
  void finish(pid_t pid, int status);
  // Prints the finished tasks' lines that come next in task order.
  void flushLines();

  const std::vector<SweepTask>& tasks_;
  const unsigned cores_;
  std::vector<const SweepTask*> pending_;
  unsigned slots_ = 0, threadsEach_ = 0;
  std::string exe_;
  std::map<pid_t, RunningTask> running_;
  std::map<long, std::string> lines_;  // finished, not yet printed (they print in task order)
  std::size_t next_ = 0, printed_ = 0, failedToRun_ = 0;
  unsigned busy_ = 0;
};

LocalRunner::LocalRunner(const std::vector<SweepTask>& tasks, unsigned jobs) : tasks_(tasks), cores_(usableCores()) {
  for (const SweepTask& t : tasks_) {
    if (!finishedResult(t)) pending_.push_back(&t);
  }
  if (jobs == 0) jobs = cores_;
  slots_ = static_cast<unsigned>(std::min<std::size_t>(jobs, std::max<std::size_t>(pending_.size(), 1)));
  threadsEach_ = std::max(1u, cores_ / slots_);
}

int LocalRunner::run() {
  const std::size_t done = tasks_.size() - pending_.size();
  std::printf("sweep: %zu tasks, %zu finished already, running %zu: %u at a time, %u thread%s each, on %u cores\n",
              tasks_.size(), done, pending_.size(), slots_, threadsEach_, threadsEach_ == 1 ? "" : "s", cores_);
  std::fflush(stdout);
  exe_ = selfExecutable();
  while (next_ < pending_.size() || !running_.empty()) {
    startTasks();
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid <= 0) {
      if (interrupted()) return stop();
      std::vector<pid_t> children;
      for (const auto& [child, r] : running_) children.push_back(child);
      waitForAChild(children);
      continue;
    }
    finish(pid, status);
  }
  const std::size_t missing = gatherSweep(tasks_);
  if (failedToRun_ > 0 || missing > 0) {
    std::fprintf(stderr, "springy sweep: %zu tasks have no result; run the sweep again to retry them\n", missing);
    return 1;
  }
  return 0;
}

void LocalRunner::startTasks() {
  while (!interrupted() && next_ < pending_.size() && running_.size() < slots_) {
    const SweepTask& t = *pending_[next_];
    const unsigned own = ownThreads(t);
    const unsigned need = std::min(own ? own : threadsEach_, cores_);
    if (!running_.empty() && busy_ + need > cores_) break;  // a task asking for many threads waits for room
    running_[spawnTask(exe_, t, own ? 0 : threadsEach_)] = {&t, need, std::chrono::steady_clock::now()};
    busy_ += need;
    ++next_;
  }
}

int LocalRunner::stop() {
  int status = 0;
  for (const auto& [child, r] : running_) kill(child, SIGTERM);
  while (!running_.empty()) {
    const pid_t gone = waitpid(-1, &status, 0);
    if (gone < 0 && errno != EINTR) break;
    running_.erase(gone);
  }
  std::fprintf(stderr, "springy sweep: interrupted; %zu of %zu tasks finished, run the sweep again to resume\n",
               static_cast<std::size_t>(std::count_if(
                   tasks_.begin(), tasks_.end(), [](const SweepTask& t) { return finishedResult(t).has_value(); })),
               tasks_.size());
  return interruptedExitStatus();
}

void LocalRunner::finish(pid_t pid, int status) {
  const auto it = running_.find(pid);
  if (it == running_.end()) return;
  const RunningTask r = it->second;
  running_.erase(it);
  busy_ -= r.threads;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - r.start).count();
  const std::optional<Json> result = finishedResult(*r.task);
  char head[64];
  std::snprintf(head, sizeof head, "[%ld/%zu] ", r.task->index + 1, tasks_.size());
  std::string line = head + describe(*r.task) + ": ";
  if (result) {
    line += (*result)["status"].get<std::string>();
    // The message's first sentence (the table has all of it).
    const std::string message = (*result)["message"].get<std::string>();
    if (!message.empty()) line += " (" + message.substr(0, message.find(". ")) + ")";
  } else {
    ++failedToRun_;
    line += WIFSIGNALED(status) ? "run-task killed by signal " + std::to_string(WTERMSIG(status))
                                : "run-task failed (exit " + std::to_string(WEXITSTATUS(status)) + ")";
    line += ", no result; see " + r.task->log;
  }
  char time[32];
  std::snprintf(time, sizeof time, ", %.2f s", seconds);
  lines_[r.task->index] = line + time;
  flushLines();
}

void LocalRunner::flushLines() {
  while (printed_ < pending_.size() && lines_.count(pending_[printed_]->index)) {
    std::printf("%s\n", lines_[pending_[printed_]->index].c_str());
    ++printed_;
  }
  std::fflush(stdout);
}

// Runs the unfinished tasks, `jobs` at a time and no more threads than cores in all; each task a
// run-task child with its output in its log. Progress lines come in task order. Returns the exit
// status.
int runLocally(const std::vector<SweepTask>& tasks, unsigned jobs) {
  LocalRunner runner(tasks, jobs);
  return runner.run();
}

// `text` quoted for sh (the job scripts' exec line): any bytes, a newline included.
std::string shellQuoted(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Runs sbatch with `args` in `directory` (no shell); returns what it printed. Throws
// springy::Error with its output when it fails.
std::string runSbatch(const std::vector<std::string>& args, const std::string& directory) {
  const std::string sbatch = findProgram("sbatch");
  if (sbatch.empty()) throw Error("sbatch is not on PATH: is Slurm's client installed (Debian: slurm-client)?");
  const ChildOutput r = runCapturing(sbatch, args, directory);
  if (interrupted()) throw Error("sbatch: interrupted");
  if (r.status != 0) throw Error("sbatch " + args.back() + " failed (exit " + std::to_string(r.status) + ")\n" + r.output);
  return r.output;
}

// The job id of `sbatch --parsable`'s "ID" or "ID;CLUSTER".
std::string jobId(const std::string& output, const std::string& command) {
  const std::string id = output.substr(0, output.find_first_of(";\n"));
  if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos) {
    throw Error("'" + command + "' printed no job id: " + output);
  }
  return id;
}

int submitToSlurm(const SweepOptions& options, const std::vector<SweepTask>& tasks, const std::string& directory) {
  // No name in the scripts but springy's own path, quoted: sbatch runs in the sweep's folder (this
  // process's working directory), which the jobs then start in, so the logs and the manifest are
  // named relative to it, and the user's sbatch arguments go on its command line. A folder named
  // "a\n#SBATCH ..." or "x; rm -rf ~" is only ever a working directory.
  const std::string exe = shellQuoted(selfExecutable());
  makeDirectories("slurm", "slurm");
  makeDirectories("logs", "logs");
  const unsigned k = options.maxRunning ? options.maxRunning : static_cast<unsigned>(tasks.size());
  // Slurm's filename patterns: %a the array index, %4a zero-padded to four digits (sbatch(1)), so
  // a task's log is logs/NNNN.log as with the local runner. run-task reads the index from
  // SLURM_ARRAY_TASK_ID and its threads from SLURM_CPUS_PER_TASK.
  writeOwnedFile("slurm/array.sh", "#!/bin/sh\n#SBATCH --job-name=springy-sweep\n#SBATCH --array=0-" +
                                            std::to_string(tasks.size() - 1) + "%" + std::to_string(k) +
                                            "\n#SBATCH --cpus-per-task=" + std::to_string(options.cpusPerTask) +
                                            "\n#SBATCH --ntasks=1\n#SBATCH --output=logs/%4a.log\nexec " + exe +
                                            " run-task manifest.jsonl\n",
                 "springy sweep writes a file of that name");
  writeOwnedFile("slurm/gather.sh",
                 "#!/bin/sh\n#SBATCH --job-name=springy-gather\n#SBATCH --ntasks=1\n"
                 "#SBATCH --output=logs/gather.log\nexec " +
                     exe + " gather manifest.jsonl\n",
                 "springy sweep writes a file of that name");
  std::vector<std::string> submit = {"--parsable"};
  submit.insert(submit.end(), options.sbatchArgs.begin(), options.sbatchArgs.end());
  std::vector<std::string> submitArray = submit;
  submitArray.push_back("slurm/array.sh");
  const std::string array = jobId(runSbatch(submitArray, ""), "sbatch slurm/array.sh");
  // afterok: the gather starts when every task of the array has ended with exit status 0 (a task
  // whose check failed still ends so: its result holds the failure).
  std::vector<std::string> submitGather = submit;
  submitGather.insert(submitGather.end(), {"--dependency=afterok:" + array, "slurm/gather.sh"});
  const std::string gather = jobId(runSbatch(submitGather, ""), "sbatch slurm/gather.sh");
  writeOwnedFile("slurm/jobs", "array " + array + "\ngather " + gather + "\n", "springy sweep writes a file of that name");
  std::printf(
      "sweep: submitted job array %s (%zu tasks, at most %u at once, %u cpus each) and gather job %s (after "
      "it); the table will be %s/table.csv\n",
      array.c_str(), tasks.size(), k, options.cpusPerTask, gather.c_str(), directory.c_str());
  return 0;
}

// Redirects standard error into a temporary file while a task runs, then passes it on; the last
// "springy" line is the task's error.
class StderrCapture {
 public:
  StderrCapture() : file_(std::tmpfile()), saved_(dup(2)) {
    if (file_ && saved_ >= 0) dup2(fileno(file_), 2);
  }
  ~StderrCapture() { finish(); }
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;

  // Restores standard error, copies what was captured to it, and returns it.
  std::string finish() {
    if (!file_) return text_;
    std::cerr.flush();
    std::fflush(stderr);
    if (saved_ >= 0) {
      dup2(saved_, 2);
      close(saved_);
      saved_ = -1;
    }
    std::rewind(file_);
    char buffer[4096];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, file_)) > 0) text_.append(buffer, n);
    std::fclose(file_);
    file_ = nullptr;
    std::cerr << text_;
    return text_;
  }

 private:
  std::FILE* file_;
  int saved_;
  std::string text_;
};

std::string lastErrorLine(const std::string& text) {
  std::string last;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("springy", 0) == 0) last = line;
  }
  return last;
}

long taskIndex(const RunTaskOptions& options) {
  if (options.index) return *options.index;
  const auto fromEnv = [](const char* name, long offset) -> std::optional<long> {
    const char* value = std::getenv(name);
    if (!value || !*value) return std::nullopt;
    long index = 0;
    const std::string_view text(value);
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), index);
    if (ec != std::errc() || end != text.data() + text.size() || index - offset < 0) {
      throw Error(std::string(name) + "=" + value + ": not a task index");
    }
    return index - offset;
  };
  // Slurm job arrays; Kubernetes indexed jobs; GNU parallel's job sequence number, from 1.
  if (auto i = fromEnv("SLURM_ARRAY_TASK_ID", 0)) return *i;
  if (auto i = fromEnv("JOB_COMPLETION_INDEX", 0)) return *i;
  if (auto i = fromEnv("PARALLEL_SEQ", 1)) return *i;
  throw Error("run-task: no --index, and none of SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, PARALLEL_SEQ is set");
}

// The task's command, with --threads from run-task's --threads, else $SLURM_CPUS_PER_TASK, unless
// the command sets them.
std::vector<std::string> taskArguments(const SweepTask& task, const RunTaskOptions& options) {
  std::vector<std::string> args = task.command;
  if (std::find(args.begin(), args.end(), "--threads") == args.end()) {
    std::string threads = options.threads ? std::to_string(*options.threads) : std::string();
    if (const char* slurm = std::getenv("SLURM_CPUS_PER_TASK"); threads.empty() && slurm && *slurm) threads = slurm;
    if (!threads.empty()) args.insert(args.end(), {"--threads", threads});
  }
  return args;
}

// Runs a task's command in this process, as main() would, with its standard error captured (and
// passed on); check's records go to `records`, its last error line to `message`. Returns the
// command's exit status (1 where it threw).
int runTaskCommand(const std::vector<std::string>& args, std::vector<SceneRecord>& records, std::string& message) {
  int status = 1;
  StderrCapture capture;
  CommandLine cli;
  try {
    parseCommandLine(cli, args);
    cli.check.records = &records;
    status = cli.dispatch();
  } catch (const CLI::ParseError& e) {
    std::cerr << "springy run-task: " << e.what() << "\n";
  } catch (const Error& e) {
    std::cerr << "springy: " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "springy: unexpected error: " << e.what() << "\n";
  }
  std::fflush(stdout);
  message = lastErrorLine(capture.finish());
  return status;
}

// The task's state: ok or failed by its exit status; for check, its records' worst status (error
// without records), and the message of the first record that is not ok in place of `message`.
std::string taskState(const SweepTask& task, int status, const std::vector<SceneRecord>& records,
                      std::string& message) {
  std::string state = status == 0 ? "ok" : "failed";
  if (task.command.front() == "check") {
    state = records.empty() ? "error" : "ok";
    message = records.empty() ? message : "";
    for (const SceneRecord& r : records) {
      if (r.status == SceneRecord::Status::Ok) continue;
      if (state == "ok" || r.status == SceneRecord::Status::Error) state = statusName(r.status);
      if (message.empty()) message = r.message;
    }
  }
  return state;
}

// The task's result file's content: its command, state, exit status, message, check's records,
// and the files in its output directory.
Json taskResult(long index, const SweepTask& task, const std::string& state, int status, const std::string& message,
                const std::vector<SceneRecord>& records) {
  Json result;
  result["task"] = index;
  result["command"] = task.command;
  result["status"] = state;
  result["exit"] = status;
  result["message"] = message;
  result["records"] = Json::array();
  for (const SceneRecord& r : records) result["records"].push_back(toJson(r));
  result["outputs"] = Json::array();
  if (!task.directory.empty() && isDirectory(task.directory)) {
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(task.directory)) {
      if (entry.path().filename().string().front() != '.')
        files.push_back((fs::path(task.directory) / entry.path().filename()).string());
    }
    std::sort(files.begin(), files.end());
    result["outputs"] = files;
  }
  return result;
}

}  // namespace

std::string enterManifestDirectory(const std::string& manifest) {
  const fs::path path(manifest);
  const fs::path dir = path.parent_path();
  if (!dir.empty() && chdir(dir.c_str()) != 0) {
    throw Error(manifest + ": cannot enter its directory: " + errorText(errno));
  }
  return path.filename().string();
}

Json readJsonFile(const std::string& path, std::uintmax_t maxBytes) {
  checkInputFile(path, maxBytes, "JSON file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open it");
  try {
    return Json::parse(in);
  } catch (const Json::exception& e) {
    throw Error(path + ": not valid JSON: " + e.what());
  }
}

std::vector<SweepTask> readManifest(const std::string& path) {
  checkInputFile(path, kMaxManifestBytes, "manifest");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the manifest");
  std::vector<SweepTask> tasks;
  long lineNumber = 0;
  for (std::string text; std::getline(in, text);) {
    ++lineNumber;
    const std::string at = path + ":" + std::to_string(lineNumber);
    SweepTask t;
    try {
      const Json line = Json::parse(text);
      t.index = line.at("task").get<long>();
      t.scene = line.at("scene").get<std::string>();
      t.point = line.at("point");
      t.command = line.at("command").get<std::vector<std::string>>();
      t.result = line.at("outputs").at("result").get<std::string>();
      t.log = line.at("outputs").at("log").get<std::string>();
      if (line["outputs"].contains("directory")) t.directory = line["outputs"]["directory"].get<std::string>();
    } catch (const Json::exception& e) {
      throw Error(at + ": not a task: " + e.what());
    }
    if (t.index != static_cast<long>(tasks.size())) {
      throw Error(at + ": task " + std::to_string(t.index) + " where task " + std::to_string(tasks.size()) +
                  " belongs (line k holds task k - 1)");
    }
    if (t.command.empty()) throw Error(at + ": the task has no command");
    tasks.push_back(std::move(t));
  }
  if (tasks.empty()) throw Error(path + ": the manifest has no tasks");
  return tasks;
}

std::optional<Json> finishedResult(const SweepTask& task) {
  if (access(task.result.c_str(), F_OK) != 0) return std::nullopt;
  try {
    Json result = readJsonFile(task.result, kMaxResultBytes);
    if (result.value("task", -1L) == task.index && result.contains("command") &&
        result["command"] == Json(task.command) && result.contains("status") && result.contains("message")) {
      return result;
    }
  } catch (const Error&) {
  }
  return std::nullopt;
}

namespace {

// Before a sweep plans anything in its folder (the working directory): the files of the names it
// writes there (manifest.jsonl, table.csv, table.json, map-*.png, and slurm/'s scripts when it
// submits) must be springy's, as the folder's record lists them (app/atomic_file.h).
void refuseOthersSweepFiles(bool slurm) {
  const auto top = [](const std::string& name) {
    return name == "manifest.jsonl" || name == "table.csv" || name == "table.json" ||
           (name.rfind("map-", 0) == 0 && name.size() > 8 && name.compare(name.size() - 4, 4, ".png") == 0);
  };
  refuseUnownedIn(".", top, "springy sweep writes (manifest.jsonl, table.csv, table.json, map-*.png)");
  if (slurm && isDirectory("slurm")) {
    const auto scripts = [](const std::string& name) {
      return name == "array.sh" || name == "gather.sh" || name == "jobs";
    };
    refuseUnownedIn("slurm", scripts, "springy sweep --slurm writes (array.sh, gather.sh, jobs)");
  }
}

}  // namespace

int runSweep(const SweepOptions& options) {
  const fs::path specPath = fs::absolute(options.spec);
  const Spec spec = readSpec(options.spec);
  const std::string output = options.output.empty() ? specPath.stem().string() + ".sweep" : options.output;
  makeDirectories(output, "-o");
  const fs::path directory = fs::weakly_canonical(fs::absolute(output));
  // The scenes as seen from the output directory, where every task runs.
  std::vector<std::string> scenes;
  for (std::size_t i = 0; i < spec.scenes.size(); ++i) {
    const fs::path scene = fs::weakly_canonical(specPath.parent_path() / spec.scenes[i]);
    if (!fs::is_regular_file(scene)) {
      fail(spec, *spec.scenesNode->as_array()->get(i), "key 'scenes': " + spec.scenes[i] + ": no such scene file");
    }
    scenes.push_back(scene.lexically_relative(directory).string());
  }
  if (chdir(directory.c_str()) != 0) throw Error(output + ": cannot enter the directory: " + errorText(errno));
  refuseOthersSweepFiles(options.slurm);
  std::vector<PlannedTask> planned = planTasks(spec, scenes);
  validateTasks(spec, planned);
  std::string manifest;
  std::vector<SweepTask> tasks;
  for (PlannedTask& p : planned) {
    manifest += manifestLine(p.task);
    tasks.push_back(std::move(p.task));
  }
  writeOwnedFile("manifest.jsonl", manifest, "springy sweep writes a file of that name");
  std::printf("sweep: %s/manifest.jsonl: %zu tasks (%s)\n", directory.c_str(), tasks.size(), spec.command.c_str());
  std::fflush(stdout);
  if (options.slurm) return submitToSlurm(options, tasks, directory.string());
  if (options.manifestOnly) return 0;
  return runLocally(tasks, options.jobs);
}

int runTask(const RunTaskOptions& options) {
  const long index = taskIndex(options);
  const std::vector<SweepTask> tasks = readManifest(options.manifest);
  enterManifestDirectory(options.manifest);
  if (index >= static_cast<long>(tasks.size())) {
    throw Error(options.manifest + ": no task " + std::to_string(index) + " (it has " + std::to_string(tasks.size()) +
                ", from 0)");
  }
  const SweepTask& task = tasks[static_cast<std::size_t>(index)];
  if (finishedResult(task)) {
    std::printf("task %ld: finished already (%s)\n", index, task.result.c_str());
    return 0;
  }
  const std::vector<std::string> args = taskArguments(task, options);
  makeDirectories(fs::path(task.result).parent_path().string(), "results");
  AtomicFile resultFile(task.result);  // an unwritable result fails before the work
  std::printf("task %ld: springy", index);
  for (const std::string& a : args) std::printf(" %s", a.c_str());
  std::printf("\n");
  std::fflush(stdout);

  std::vector<SceneRecord> records;
  std::string message;
  const int status = runTaskCommand(args, records, message);
  if (interrupted()) {
    std::cerr << "springy run-task: task " << index << " interrupted; no result\n";
    return interruptedExitStatus();
  }
  const std::string state = taskState(task, status, records, message);
  resultFile.write(taskResult(index, task, state, status, message, records).dump(2) + "\n");
  resultFile.commit();
  std::printf("task %ld: %s%s%s\n", index, state.c_str(), message.empty() ? "" : ": ", message.c_str());
  // Recorded, whatever the check found: a scheduler's afterok then still runs the gather.
  return 0;
}

int runGather(const GatherOptions& options) {
  const std::vector<SweepTask> tasks = readManifest(options.manifest);
  enterManifestDirectory(options.manifest);
  return gatherSweep(tasks) == 0 ? 0 : 1;
}

}  // namespace springy

// springy app: what `sweep`, `run-task` and `gather` share (app/sweep.cpp, app/gather.cpp): the
// manifest, one task per line, and the tasks' results.
//
// A manifest line (JSON):
//   {"task": 3, "scene": "../scenes/a.toml", "point": {"dt": 0.002, "environment.drag": 0.5},
//    "command": ["check", "../scenes/a.toml", "--dt", "0.002", "--set", "environment.drag=0.5"],
//    "outputs": {"result": "results/0003.json", "log": "logs/0003.log"}}
// Paths are relative to the manifest's directory, where run-task and gather work. `command` is a
// springy command line (without the program's name): run-task runs exactly it, in-process.
// "outputs" also has "directory" ("outputs/0003/") for render and frames.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "run/records.h"

namespace springy {

struct SweepTask {
  long index = 0;
  std::string scene;
  Json point;  // key -> value, in the spec's order
  std::vector<std::string> command;
  std::string result, log, directory;  // directory: empty for check
};

// The manifest's tasks; line k must be task k. Throws springy::Error "PATH:LINE: ...".
std::vector<SweepTask> readManifest(const std::string& path);

// Makes the manifest's directory the working directory (the tasks' paths are relative to it) and
// returns the manifest's name there.
std::string enterManifestDirectory(const std::string& manifest);

// The task's result when it is finished: a complete result file (written atomically) of this very
// command. A result of another command (the spec changed) does not count.
std::optional<Json> finishedResult(const SweepTask& task);

// JSON from a file of at most `maxBytes`. Throws springy::Error naming the file.
Json readJsonFile(const std::string& path, std::uintmax_t maxBytes);

// Collects the results of every task into table.csv and table.json, and for a check sweep over
// two keys per scene a map, map-SCENE.png. Returns the number of tasks without a result (listed
// as "missing").
std::size_t gatherSweep(const std::vector<SweepTask>& tasks);

}  // namespace springy

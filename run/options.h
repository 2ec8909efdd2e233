// springy run: the options of a run, as one list.
//
// Every front end that runs a scene (check, export, report, render, frames, sweep tasks and the
// Python module) takes the same options, read from one table (runOptionTable): the command line
// adds an option per row (app/cli.cpp), the Python module takes a keyword per row
// (springy.load(path, integrator="vbd", iterations=4)), and both hand the text to the row's
// setter, which checks it and names the option in its error. A new option is one row here and
// one field in RunOptions: it reaches the command line, Python and the sweeps at once
// (tests/python/test_options.py walks the command line's options and finds each in Python).
// The scene gives the same settings as keys ([scene] integrator, dt, substeps, tolerance,
// iterations, duration); an option given here wins (run/load.h loadSceneWith).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace springy {

struct RunOptions {
  // How the scene is stepped.
  std::optional<std::string> integrator;  // --integrator NAME
  std::optional<double> dt;               // --dt SECONDS
  std::optional<double> tolerance;        // --tolerance: an adaptive integrator at this tolerance
  std::optional<int> substeps;            // --substeps N
  bool autoSubsteps = false;              // --substeps auto: the stability advisor picks them
  std::optional<int> iterations;          // --iterations: vbd's sweeps per step
  std::optional<double> duration;         // --duration SECONDS
  std::optional<unsigned> threads;        // --threads (default: SPRINGY_THREADS, else every core)
  // --set KEY=VALUE: scene keys set before the scene is read (run/load.h loadSceneSetting).
  std::vector<std::string> sets;
  // check's criteria: a run that passes the monitor fails them (Failure::criterion).
  double minVolume = 0.0;  // --min-volume: a body's volume below this fraction of rest, ever
  double endVolume = 0.0;  // --end-volume: a body ending below this fraction of its rest volume
  bool endAtRest = false;  // --end-at-rest: every body at rest (sim/monitor.h) through the last second
};

// One row of the table.
struct RunOption {
  enum class Group { Run, Criteria };  // criteria: the commands that judge a run (check, export, report, Python)
  std::string name;   // Python's keyword: "integrator", "min_volume"
  std::string flag;   // the command line's: "--integrator", "--min-volume"
  std::string value;  // what it takes, for help ("SECONDS"); empty for a flag that takes none
  std::string help;
  Group group = Group::Run;
  bool repeatable = false;  // --set: each use adds one
  // Sets the option from its text, as typed after the flag ("true" or "false" for a flag that
  // takes none). Throws springy::Error naming the flag and what it takes.
  void (*set)(RunOptions& options, const std::string& text) = nullptr;
};

// Every option, in the order the command line's help lists them.
const std::vector<RunOption>& runOptionTable();

// The row whose name ("min_volume") or flag ("--min-volume") this is, or null.
const RunOption* findRunOption(std::string_view nameOrFlag);

// Sets the option `name` (a row's name or flag) from its text; throws springy::Error for a name
// no row has (listing the names) or a bad value.
void setRunOption(RunOptions& options, std::string_view name, const std::string& text);

// Checks every option's range (what setRunOption checks after each; loadSceneWith before a
// run): throws springy::Error naming the flag and its range.
void checkRunOptions(const RunOptions& options);

// The most simulation threads a run takes (--threads).
constexpr unsigned kMaxThreads = 256;

// The simulation threads the options ask for: --threads, else defaultThreadCount().
unsigned threadCount(const RunOptions& options);

// springy study's own options, read from their text by the command line (app/cli.cpp) and by
// Python's springy.study() alike, so that both refuse the same values with the same words. Each
// throws springy::Error naming the option and what it takes.
constexpr int kMaxStudyRepeats = 1000;
std::string studyKind(const std::string& text);      // KIND: accuracy, contact or stability
int studyRepeats(const std::string& text);           // --repeats N: 1 to kMaxStudyRepeats
double studyMaxDuration(const std::string& text);    // --max-duration SECONDS: positive and finite

}  // namespace springy

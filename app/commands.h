// springy app: the subcommands.
#pragma once

#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "app/records.h"
#include "app/runner.h"

namespace springy {

struct CheckOptions {
  std::vector<std::string> scenes;
  RunOverrides overrides;
  std::string trace;  // CSV path, empty for none
  double minVolume = 0.0;  // fail when a body's volume falls below this fraction of rest
  double endVolume = 0.0;  // fail when a body ends below this fraction of its rest volume
  bool endAtRest = false;  // fail unless every body is at rest (sim/monitor.h) through the last second
  std::string json;        // --json FILE: the records (app/records.h), empty for none
  std::string junit;       // --junit FILE: the records as JUnit XML, empty for none
  std::vector<SceneRecord>* records = nullptr;  // when set, also receives the records (sweep's run-task)
  // --export OUT (`springy export -o OUT`): the run's motion (app/export.h), a file for one scene or
  // a directory that gets SCENE.EXT for each (EXT from exportFormat); empty for none.
  std::string exportOutput;
  std::string exportFormat = "glb";  // for a directory: pc2, glb or pvd
  std::string command = "check";          // the command run, for messages ("export")
  std::string exportOption = "--export";  // the option that named exportOutput, for messages ("-o" in `export`)
  // For `report`: exportOutput (one scene) is the page's 3D replay (openReplay), and it is kept
  // when the run failed only a criterion; onFrame, when set, sees every frame after it was
  // checked (k = 1, 2, ...; k = 1 again when the default step's try failed and the run restarts).
  bool replay = false;
  bool exportOnCriterionFailure = false;
  std::function<void(long k, const World& world, const Monitor& monitor)> onFrame;
};
int runCheck(const CheckOptions& options);

// The file each scene's motion is exported to: -o names a file with a format's extension (one
// scene), or a directory (it exists, ends in '/', or there are several scenes) that gets
// SCENE.EXT for each, EXT given by `format`. Creates the directory; throws springy::Error.
std::vector<std::string> exportOutputs(const std::vector<std::string>& scenes, const std::string& output,
                                       const std::string& format, const std::string& option);

// Command-line overrides of a scene's [render] table.
struct RenderOverrides {
  std::optional<int> width, height, crf;
  std::optional<double> fps;
  std::optional<std::string> preset;
  bool noOverlay = false, noShadows = false, noAntialias = false;
};

// Applies them to the scene, with the same ranges as the scene's [render] keys (scene.cpp) and a
// message naming the option: a value out of range is a springy::Error, never clamped.
void applyRenderOverrides(SceneDesc& scene, const RenderOverrides& overrides);

struct RenderOptions {
  std::vector<std::string> scenes;
  std::string output;  // a file for one scene, or a directory
  RunOverrides overrides;
  RenderOverrides render;
};
int runRender(const RenderOptions& options);

struct FramesOptions {
  std::vector<std::string> scenes;
  std::string output = ".";  // directory
  std::string times;         // comma-separated seconds; empty: eight evenly spaced
  bool sheet = false;        // also a contact sheet
  bool sheetOnly = false;    // only the contact sheet
  RunOverrides overrides;
  RenderOverrides render;
};
int runFrames(const FramesOptions& options);

// The stability advisor on a loaded scene. Warn: warns when the step exceeds the estimated
// stable limit. AutoSubsteps (--substeps auto): sets scene.substeps to the survey's count, tried
// over the whole run and doubled or halved until it is within a factor 2 of the fewest that pass.
// Default (neither the scene nor the command line gave dt or substeps): the estimate at rest with
// the margin that holds through impacts (impactMargin, sim/setup.h), tried and doubled until it
// passes. Both say what they chose. The tries run on `threads` threads. With `runIsTry` (check,
// render and frames, whose own runs are monitored as a try is), the default step is not tried
// first: the caller runs it and, if its run fails, calls retryDefaultStep.
enum class StepChoice { Warn, AutoSubsteps, Default };
void adviseTimeStep(const std::string& path, SceneDesc& scene, StepChoice choice, unsigned threads, std::ostream& log,
                    bool runIsTry = false);
// A run that was the default step's try (`untried`: check, render and frames with runIsTry)
// failed: unless the failure is a limit the run was given (Failure::criterion), tries twice the
// count and on, doubling, as adviseTimeStep does, sets scene.substeps to the count that passed,
// says so, clears `untried` and returns true: the caller runs the scene again. False when the run
// was no try or the failure a criterion (the caller reports it); throws springy::Error when no
// count up to kMaxSubsteps passes.
bool retryDefaultStep(const std::string& path, SceneDesc& scene, const Failure& failure, bool& untried,
                      unsigned threads, std::ostream& log);

struct SuggestOptions {
  std::vector<std::string> scenes;
  RunOverrides overrides;
  double keepVolume = 0.85;  // the fraction of its rest volume a body should keep through impacts
};
int runSuggest(const SuggestOptions& options);

struct StudyOptions {
  std::string kind;               // "accuracy", "contact" or "stability"
  std::string output = "study";   // directory
  std::vector<std::string> scenes;  // showcase scenes for the accuracy study
  bool quick = false;
  int repeats = 3;
  double maxDuration = 0;  // contact: study at most this much of each scene [s] (0: all)
};
int runStudy(const StudyOptions& options);

// `springy report` (app/report.cpp, docs/report.md): HTML pages of scenes' runs, a sweep, a study.
struct ReportOptions {
  std::vector<std::string> scenes;
  std::string output;       // the report's folder
  RunOverrides overrides;   // for every scene's run (check's, the video's, the sheet's)
  double minVolume = 0.0, endVolume = 0.0;  // check's criteria, shown in the pages
  bool endAtRest = false;
  std::string sweep;        // a sweep's folder (its table.json), empty for none
  std::string x, y;         // the sweep's plot: the key across (default: the first swept) and the figure
  std::string study;        // a study's folder (its .md pages and plots), empty for none
  std::vector<std::string> command;  // the command line, shown on the overview
};
int runReport(const ReportOptions& options);

// `springy sweep SPEC.toml` (app/sweep.cpp, docs/sweeps.md).
struct SweepOptions {
  std::string spec;
  std::string output;         // directory; empty: SPEC's stem + ".sweep" in the working directory
  unsigned jobs = 0;          // tasks at once (0: one per core)
  bool manifestOnly = false;  // write the manifest, run nothing
  bool slurm = false;         // submit a job array and a gather job
  unsigned cpusPerTask = 1;   // Slurm --cpus-per-task
  unsigned maxRunning = 0;    // Slurm --array=0-N%K (0: no limit)
  std::vector<std::string> sbatchArgs;
};
int runSweep(const SweepOptions& options);

struct RunTaskOptions {
  std::string manifest;
  std::optional<long> index;
  std::optional<unsigned> threads;
};
int runTask(const RunTaskOptions& options);

struct GatherOptions {
  std::string manifest;
};
int runGather(const GatherOptions& options);

}  // namespace springy

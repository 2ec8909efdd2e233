// springy app: the subcommands.
#pragma once

#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "run/records.h"
#include "run/run.h"

namespace springy {

struct CheckOptions {
  std::vector<std::string> scenes;
  RunOptions run;     // how each scene runs, and check's criteria (run/options.h)
  std::string trace;  // CSV path, empty for none
  std::string json;   // --json FILE: the records (run/records.h), empty for none
  std::string junit;  // --junit FILE: the records as JUnit XML, empty for none
  std::vector<SceneRecord>* records = nullptr;  // when set, also receives the records (sweep's run-task)
  // --export OUT (`springy export -o OUT`): the run's motion (app/export.h), a file for one scene or
  // a directory that gets SCENE.EXT for each (EXT from exportFormat); empty for none.
  std::string exportOutput;
  std::string exportFormat = "glb";  // for a directory: pc2, glb or pvd
  std::string command = "check";          // the command run, for messages ("export")
  std::string exportOption = "--export";  // the option that named exportOutput, for messages ("-o" in `export`)
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
  RunOptions run;
  RenderOverrides render;
};
int runRender(const RenderOptions& options);

struct FramesOptions {
  std::vector<std::string> scenes;
  std::string output = ".";  // directory
  std::string times;         // comma-separated seconds; empty: eight evenly spaced
  bool sheet = false;        // also a contact sheet
  bool sheetOnly = false;    // only the contact sheet
  RunOptions run;
  RenderOverrides render;
};
int runFrames(const FramesOptions& options);

struct SuggestOptions {
  std::vector<std::string> scenes;
  RunOptions run;
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
  RunOptions run;           // every scene's run (--width, --height, --fps as --set render.* keys), and
                            // check's criteria (shown in the pages)
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

#include "app/cli.h"

#include <algorithm>
#include <iostream>
#include <filesystem>

#include "app/atomic_file.h"
#include "app/child.h"
#include "sim/error.h"
#include "sim/limits.h"

namespace springy {
namespace {

#ifdef SPRINGY_RENDER_HELPER
constexpr const char* kRenderHelper = SPRINGY_RENDER_HELPER;
#else
constexpr const char* kRenderHelper = nullptr;
#endif

// A fraction in [0, 1]; CLI::Range lets NaN through (every comparison with it is false).
const CLI::Validator kFraction(
    [](const std::string& text) -> std::string {
      double value = 0.0;
      try {
        std::size_t used = 0;
        value = std::stod(text, &used);
        if (used != text.size()) return "expected a number in [0, 1], got '" + text + "'";
      } catch (const std::exception&) {
        return "expected a number in [0, 1], got '" + text + "'";
      }
      return value >= 0.0 && value <= 1.0 ? std::string() : "expected a number in [0, 1], got '" + text + "'";
    },
    "FRACTION in [0, 1]");

// An output's name (-o, --trace, --json, ...): an empty one would fall back to a default place
// (the working directory) or to writing nothing at all, silently.
const CLI::Validator kOutputName(
    [](const std::string& text) -> std::string {
      return text.empty() ? "the output's name is empty: give a file or a folder" : std::string();
    },
    "NAME");

// The run options (run/options.h), one CLI11 option per row of the table: the row's setter
// checks the text and its error becomes CLI11's, so a bad value fails the parse with the message
// the Python module gives for it too. `criteria`: also check's criteria (--min-volume, ...).
void addRunOptions(CLI::App* cmd, RunOptions& o, bool criteria) {
  for (const RunOption& row : runOptionTable()) {
    if (row.group == RunOption::Group::Criteria && !criteria) continue;
    auto set = [&o, &row](const std::string& text) {
      try {
        row.set(o, text);
        checkRunOptions(o);
      } catch (const Error& e) {
        throw CLI::ValidationError(e.what());
      }
    };
    CLI::Option* option =
        row.value.empty() ? cmd->add_flag_callback(row.flag, [set] { set("true"); }, row.help)
        : row.repeatable  ? cmd->add_option_function<std::vector<std::string>>(
                               row.flag,
                               [set](const std::vector<std::string>& texts) {
                                 for (const std::string& text : texts) set(text);
                               },
                               row.help)
                                ->allow_extra_args(false)
                          : cmd->add_option_function<std::string>(row.flag, set, row.help);
    if (!row.value.empty()) option->type_name(row.value);
  }
}

// A CLI11 callback that reads an option's text with `parse` (run/options.h: the same check
// Python's springy.study() makes), its springy::Error becoming CLI11's, so the parse fails with
// the words Python raises.
template <class T, class Parse>
std::function<void(const std::string&)> parsedInto(T& target, Parse parse) {
  return [&target, parse](const std::string& text) {
    try {
      target = parse(text);
    } catch (const Error& e) {
      throw CLI::ValidationError(e.what());
    }
  };
}

void addRenderOverrides(CLI::App* cmd, RenderOverrides& o) {
  cmd->add_option("--width", o.width, "Frame width in pixels (even)");
  cmd->add_option("--height", o.height, "Frame height in pixels (even)");
  cmd->add_option("--fps", o.fps, "Frames per second");
  cmd->add_flag("--no-overlay", o.noOverlay, "No text overlay");
  cmd->add_flag("--no-shadows", o.noShadows, "No shadow pass");
  cmd->add_flag("--no-antialias", o.noAntialias, "No multisampling");
}

}  // namespace

CommandLine::CommandLine() {
  app.require_subcommand(1);
  app.set_version_flag("--version", "springy 0.1");
  // The subcommands, in the order --help lists them.
  addCheck();
  addExport();
  addSuggest();
  addStudy();
  addRender();
  addFrames();
  addReport();
  addSweep();
  addRunTask();
  addGather();
}

// Adds `check`: runs scenes and checks them; its outputs (trace, JSON, JUnit, export).
void CommandLine::addCheck() {
  checkCmd = app.add_subcommand("check", "Run scenes headlessly and check stability; per-body report");
  checkCmd->add_option("scenes", check.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  addRunOptions(checkCmd, check.run, true);
  checkCmd->add_option("--trace", check.trace, "Write per-frame centroid, volume and energies as CSV")->check(kOutputName);
  checkCmd->add_option("--json", check.json, "Write the per-body results as JSON (the records `sweep` gathers)")->check(kOutputName);
  checkCmd->add_option("--junit", check.junit,
                       "Write the results as JUnit XML: a test case per scene and body, failures with the message")
      ->check(kOutputName);

  checkCmd
      ->add_option("--export", check.exportOutput,
                   "Also write the run's motion: FILE.pc2 (Blender's point cache, with FILE.obj), FILE.glb (glTF 2.0) "
                   "or FILE.pvd (ParaView's .vtu series), or a directory (several scenes; --export-format)")
      ->check(kOutputName);
  checkCmd->add_option("--export-format", check.exportFormat, "With --export DIR: pc2, glb or pvd")
      ->check(CLI::IsMember({"pc2", "glb", "pvd"}))
      ->capture_default_str();
}

// Adds `export`: a check whose motion is written for Blender, ParaView or a glTF viewer.
void CommandLine::addExport() {
  exportCmd = app.add_subcommand(
      "export", "Simulate scenes (checked as `check` does) and write every frame of every body for Blender, "
                "ParaView or a glTF viewer (docs/export.md)");
  exportCmd->add_option("scenes", exportRun.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  exportCmd
      ->add_option("-o,--output", exportRun.exportOutput,
                   "FILE.pc2 (Blender's point cache, with FILE.obj and FILE.mtl), FILE.glb (glTF 2.0 binary) or "
                   "FILE.pvd (ParaView's time series, with the folder FILE/ of .vtu files); or a directory that "
                   "gets SCENE.EXT for each scene (--format)")
      ->required()
      ->check(kOutputName);
  exportRun.exportOption = "-o";
  exportRun.command = "export";
  exportCmd->add_option("--format", exportRun.exportFormat, "With -o DIR: pc2, glb or pvd")
      ->check(CLI::IsMember({"pc2", "glb", "pvd"}))
      ->capture_default_str();
  exportCmd->add_option("--fps", exportFps, "Frames per second written (default: the scene's [render] fps)")
      ->check(CLI::Range(1.0, 240.0));
  addRunOptions(exportCmd, exportRun.run, true);
  exportCmd->add_option("--trace", exportRun.trace, "Also write check's per-frame trace (CSV)")->check(kOutputName);
  exportCmd->add_option("--json", exportRun.json, "Also write check's per-body results as JSON")->check(kOutputName);
}

// Adds `suggest`: the stability advisor's step and values for scenes.
void CommandLine::addSuggest() {
  suggestCmd =
      app.add_subcommand("suggest", "Estimate stable dt and propose stable T, P, T_theta, P_theta for a scene");
  suggestCmd->add_option("scenes", suggest.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  addRunOptions(suggestCmd, suggest.run, false);
  suggestCmd
      ->add_option("--keep-volume", suggest.keepVolume,
                   "Volume fraction each body should keep through its first impact; suggest simulates the scene "
                   "to predict the squash, and the periods that keep this much (default 0.85)")
      ->check(kFraction);
}

// Adds `study`: the integrators' work-precision and stability studies.
void CommandLine::addStudy() {
  studyCmd = app.add_subcommand(
      "study", "Work-precision study of the integrators (accuracy: before contact; contact: whole runs), or stability");
  // KIND, --repeats and --max-duration are read as springy.study() reads them (run/options.h).
  studyCmd->add_option_function<std::string>("kind", parsedInto(study.kind, studyKind), "accuracy, contact or stability")
      ->type_name("KIND")
      ->required();
  studyCmd
      ->add_option_function<std::string>("--max-duration", parsedInto(study.maxDuration, studyMaxDuration),
                                         "contact: study at most this many seconds of each scene (default: all of it)")
      ->type_name("SECONDS");
  studyCmd->add_option("-o,--output", study.output, "Output directory (CSV, Markdown, plots)")
      ->capture_default_str()
      ->check(kOutputName);
  studyCmd
      ->add_option("--scenes", study.scenes,
                   "Scenes for the accuracy and contact studies and the stability study's whole runs (default: the showcase scenes)")
      ->check(CLI::ExistingFile);
  studyCmd->add_flag("--quick", study.quick, "Small cases and few repeats (seconds; for tests and CI)");
  studyCmd
      ->add_option_function<std::string>("--repeats", parsedInto(study.repeats, studyRepeats),
                                         "Timed runs per point (the median is reported), 1 to " +
                                             std::to_string(kMaxStudyRepeats))
      ->type_name("N")
      ->default_str(std::to_string(study.repeats));
}

// Adds `render`: MP4 videos of scenes.
void CommandLine::addRender() {
  renderCmd = app.add_subcommand("render", "Simulate scenes and encode MP4 videos (H.264)");
  renderCmd->add_option("scenes", render.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  renderCmd->add_option("-o,--output", render.output,
                        "Output .mp4 for one scene, or a directory (default: SCENE.mp4 here)")
      ->check(kOutputName);
  addRunOptions(renderCmd, render.run, false);
  addRenderOverrides(renderCmd, render.render);
  renderCmd->add_option("--crf", render.render.crf, "H.264 quality, 0-51, lower is better");
  renderCmd->add_option("--preset", render.render.preset, "x264 preset (ultrafast ... veryslow)");
}

// Adds `frames`: PNG stills and a contact sheet.
void CommandLine::addFrames() {
  framesCmd = app.add_subcommand("frames", "Write PNG stills at chosen times, and a contact sheet");
  framesCmd->add_option("scenes", frames.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  framesCmd->add_option("-o,--output", frames.output, "Output directory")->capture_default_str()->check(kOutputName);
  framesCmd->add_option("--times", frames.times, "Comma-separated times in seconds (default: 8 evenly spaced)");
  framesCmd->add_flag("--sheet", frames.sheet, "Also write SCENE_sheet.png, a labelled grid of the stills");
  framesCmd->add_flag("--sheet-only", frames.sheetOnly, "Write only the contact sheet");
  addRunOptions(framesCmd, frames.run, false);
  addRenderOverrides(framesCmd, frames.render);
}

// Adds `report`: the HTML pages of scenes' runs, a sweep and a study.
void CommandLine::addReport() {
  reportCmd = app.add_subcommand(
      "report", "Write HTML pages of scenes' runs (video, 3D replay, contact sheet, plots, check's table), a sweep "
                "and a study, to open in a browser (docs/report.md)");
  reportCmd->add_option("scenes", report.scenes, "Scene files (.toml)")->check(CLI::ExistingFile);
  reportCmd->add_option("-o,--output", report.output, "The report's folder (replaced if springy wrote it before)")
      ->required()
      ->check(kOutputName);
  addRunOptions(reportCmd, report.run, true);
  reportCmd->add_option("--width", reportWidth, "Video width in pixels (even)")->check(CLI::Range(16, 7680));
  reportCmd->add_option("--height", reportHeight, "Video height in pixels (even)")->check(CLI::Range(16, 4320));
  reportCmd->add_option("--fps", reportFps, "Frames per second (video, plots, replay)")->check(CLI::Range(1.0, 240.0));
  reportCmd->add_option("--sweep", report.sweep, "A sweep's folder (its table.json): a page with a row per task")
      ->check(CLI::ExistingDirectory);
  reportCmd->add_option("--x", report.x, "The sweep's plot: the key across (default: the first that varies)");
  reportCmd->add_option("--y", report.y,
                        "The sweep's plot: the figure up: volume_min (default), volume_end, max_strain, "
                        "max_penetration, steps, kinetic or elastic");
  reportCmd->add_option("--study", report.study, "A study's folder (springy study -o DIR): its pages and plots")
      ->check(CLI::ExistingDirectory);
}

// Adds `sweep`: a spec's tasks, run here or submitted to Slurm.
void CommandLine::addSweep() {
  sweepCmd = app.add_subcommand("sweep", "Run a scene (or several) over a grid or list of settings (docs/sweeps.md)");
  sweepCmd->add_option("spec", sweep.spec, "Sweep spec (.toml)")->required()->check(CLI::ExistingFile);
  sweepCmd->add_option("-o,--output", sweep.output,
                       "Directory of the manifest, results and table (default: SPEC's name + .sweep, here)")
      ->check(kOutputName);
  sweepCmd
      ->add_option("-j,--jobs", sweep.jobs,
                   "At most this many tasks at once (default: one per core; never more threads than cores in all)")
      ->check(CLI::Range(1u, 4096u));
  sweepCmd->add_flag("--manifest-only", sweep.manifestOnly,
                     "Write the manifest and stop (run its tasks with run-task: GNU parallel, a scheduler)");
  sweepCmd->add_flag("--slurm", sweep.slurm,
                     "Submit the tasks as a Slurm job array (sbatch), and a gather job that runs after it");
  sweepCmd->add_option("--cpus-per-task", sweep.cpusPerTask, "Slurm: cores (and simulation threads) per task")
      ->capture_default_str()
      ->check(CLI::Range(1u, 256u));
  sweepCmd->add_option("--max-running", sweep.maxRunning, "Slurm: tasks running at once (--array=0-N%K; default all)")
      ->check(CLI::Range(1u, 100000u));
  sweepCmd
      ->add_option("--sbatch-arg", sweep.sbatchArgs,
                   "Slurm: one more sbatch option for both jobs, e.g. --sbatch-arg=--partition=debug (repeatable)")
      ->allow_extra_args(false);
}

// Adds `run-task`: runs one task of a sweep's manifest.
void CommandLine::addRunTask() {
  runTaskCmd = app.add_subcommand("run-task", "Run one task of a sweep's manifest (skipped when already finished)");
  runTaskCmd->add_option("manifest", runTask.manifest, "The sweep's manifest.jsonl")->required();
  runTaskCmd
      ->add_option("--index", runTask.index,
                   "The task, from 0 (default: $SLURM_ARRAY_TASK_ID, else $JOB_COMPLETION_INDEX, else "
                   "$PARALLEL_SEQ - 1)")
      ->check(CLI::Range(0L, 100000000L));
  runTaskCmd
      ->add_option("--threads", runTask.threads,
                   "Simulation threads, unless the task sets them (default: $SLURM_CPUS_PER_TASK, else as "
                   "every command)")
      ->check(CLI::Range(1u, 256u));
}

// Adds `gather`: collects a sweep's results into its table.
void CommandLine::addGather() {
  gatherCmd = app.add_subcommand("gather", "Collect a sweep's results into its table (CSV, JSON) and map (PNG)");
  gatherCmd->add_option("manifest", gather.manifest, "The sweep's manifest.jsonl")->required();
}

int CommandLine::dispatch() {
  if (checkCmd->parsed()) return runCheck(check);
  if (exportCmd->parsed()) {
    if (exportFps) {
      char fps[64];
      std::snprintf(fps, sizeof fps, "render.fps=%.17g", *exportFps);
      exportRun.run.sets.push_back(fps);
    }
    return runCheck(exportRun);
  }
  if (suggestCmd->parsed()) return runSuggest(suggest);
  if (studyCmd->parsed()) return runStudy(study);
  if (renderCmd->parsed() || framesCmd->parsed() || reportCmd->parsed()) return dispatchDrawing();
  if (sweepCmd->parsed()) return runSweep(sweep);
  if (runTaskCmd->parsed()) return springy::runTask(runTask);
  if (gatherCmd->parsed()) return runGather(gather);
  return 0;
}

int CommandLine::dispatchDrawing() {
  const DrawingCommands& drawing = drawingCommands();
  if (!drawing.render) {
    // The drawing runs in springy-render beside this program (app/CMakeLists.txt), with the same
    // arguments, parsed here already: a bad one fails here, the same way.
    if (!kRenderHelper) throw Error("this springy was built without the renderer (-DSPRINGY_RENDER=ON builds it)");
    return runChild((std::filesystem::path(selfExecutable()).parent_path() / kRenderHelper).string(), args);
  }
  if (renderCmd->parsed()) return drawing.render(render);
  if (framesCmd->parsed()) return drawing.frames(frames);
  // The video's size and rate as scene keys: the run and the video take them alike.
  if (reportWidth) report.run.sets.push_back("render.width=" + std::to_string(*reportWidth));
  if (reportHeight) report.run.sets.push_back("render.height=" + std::to_string(*reportHeight));
  if (reportFps) {
    char fps[64];
    std::snprintf(fps, sizeof fps, "render.fps=%.17g", *reportFps);
    report.run.sets.push_back(fps);
  }
  report.command = {"springy"};
  report.command.insert(report.command.end(), args.begin(), args.end());
  return drawing.report(report);
}

DrawingCommands& drawingCommands() {
  static DrawingCommands commands;
  return commands;
}

void parseCommandLine(CommandLine& cli, std::vector<std::string> args) {
  cli.args = args;
  std::reverse(args.begin(), args.end());  // CLI11 takes them last first
  cli.app.parse(args);
}

int runMain(int argc, char** argv) {
  CommandLine cli;
  installInterruptHandler();
  try {
    cli.args.assign(argv + 1, argv + argc);
    cli.app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.app.exit(e);
  }
  try {
    return cli.dispatch();
  } catch (const Error& e) {
    std::cerr << "springy: " << e.what() << "\n";
    // Work that stopped for an interrupt (a survey, suggest's simulations, a study) ends as the
    // signal's: 130 for Ctrl-C, 143 for SIGTERM.
    return interrupted() ? interruptedExitStatus() : 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "springy: out of memory (the scene or its meshes are too large for this machine)\n";
    return 1;
  } catch (const std::exception& e) {
    // Not a user error springy foresaw (those are Error): still a message and a clean
    // exit, never std::terminate's abort, so that temporary outputs are removed.
    std::cerr << "springy: unexpected error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace springy

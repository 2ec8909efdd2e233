// springy app: the command line, built once per parse. main() parses the process's arguments
// with it; `run-task` parses a sweep task's command with a fresh one, so that a task runs exactly
// the command its manifest line shows.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/commands.h"

namespace springy {

struct CommandLine {
  CommandLine();
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  // Runs the parsed subcommand; returns its exit status. Throws springy::Error.
  int dispatch();
  // render, frames and report: drawingCommands() where this program has them, else springy-render.
  int dispatchDrawing();

  CLI::App app{"springy: soft bodies as springy meshes, simulated and rendered offscreen"};
  CheckOptions check;
  CheckOptions exportRun;  // `springy export`: a check whose motion is exported
  std::optional<double> exportFps;
  SuggestOptions suggest;
  StudyOptions study;
  RenderOptions render;
  FramesOptions frames;
  SweepOptions sweep;
  RunTaskOptions runTask;
  GatherOptions gather;
  ReportOptions report;
  std::optional<int> reportWidth, reportHeight;
  std::optional<double> reportFps;
  CLI::App* checkCmd = nullptr;
  CLI::App* exportCmd = nullptr;
  CLI::App* suggestCmd = nullptr;
  CLI::App* studyCmd = nullptr;
  std::vector<std::string> args;  // the arguments parsed (without the program's name)
  CLI::App* renderCmd = nullptr;  // null without the renderer
  CLI::App* framesCmd = nullptr;
  CLI::App* sweepCmd = nullptr;
  CLI::App* runTaskCmd = nullptr;
  CLI::App* gatherCmd = nullptr;
  CLI::App* reportCmd = nullptr;  // null without the renderer

 private:
  // Each adds its subcommand and the subcommand's options to `app` (app/cli.cpp); the constructor
  // calls them in the order --help lists them.
  void addCheck();
  void addExport();
  void addSuggest();
  void addStudy();
  void addRender();
  void addFrames();
  void addReport();
  void addSweep();
  void addRunTask();
  void addGather();
};

// Parses `args` (without the program's name) into `cli`. Throws CLI::ParseError.
void parseCommandLine(CommandLine& cli, std::vector<std::string> args);

// The commands that draw (app/render_cmd.cpp, app/report.cpp), which need the renderer's
// libraries: OSMesa (with LLVM) and FFmpeg bring about 150 shared libraries, whose loading took
// 60 ms of every run. springy-render sets them (app/render_main.cpp); springy, which does not
// link them, runs springy-render beside it for these commands, with its own arguments.
struct DrawingCommands {
  int (*render)(const RenderOptions&) = nullptr;
  int (*frames)(const FramesOptions&) = nullptr;
  int (*report)(const ReportOptions&) = nullptr;
};
DrawingCommands& drawingCommands();

// main(): parses the arguments, dispatches, and turns every error into a message and an exit
// status (app/main.cpp, app/render_main.cpp).
int runMain(int argc, char** argv);

}  // namespace springy

// springy app: the subcommands.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "app/runner.h"

namespace springy {

struct CheckOptions {
  std::vector<std::string> scenes;
  RunOverrides overrides;
  std::string trace;  // CSV path, empty for none
  double minVolume = 0.0;  // fail when a body's volume falls below this fraction of rest
  double endVolume = 0.0;  // fail when a body ends below this fraction of its rest volume
  bool endAtRest = false;  // fail unless every body is at rest (sim/monitor.h) through the last second
};
int runCheck(const CheckOptions& options);

// Command-line overrides of a scene's [render] table.
struct RenderOverrides {
  std::optional<int> width, height, crf;
  std::optional<double> fps;
  std::optional<std::string> preset;
  bool noOverlay = false, noShadows = false, noAntialias = false;
};

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
// stable limit. AutoSubsteps (--substeps auto): sets scene.substeps to a safe number. Default
// (neither the scene nor the command line gave dt or substeps): the same with the margin
// margin that holds through impacts (impactMargin, sim/setup.h). Both say what they chose.
enum class StepChoice { Warn, AutoSubsteps, Default };
void adviseTimeStep(const std::string& path, SceneDesc& scene, StepChoice choice, std::ostream& log);

struct SuggestOptions {
  std::vector<std::string> scenes;
  RunOverrides overrides;
  double keepVolume = 0.85;  // the fraction of its rest volume a body should keep through impacts
};
int runSuggest(const SuggestOptions& options);

struct StudyOptions {
  std::string kind;               // "accuracy" or "stability"
  std::string output = "study";   // directory
  std::vector<std::string> scenes;  // showcase scenes for the accuracy study
  bool quick = false;
  int repeats = 3;
};
int runStudy(const StudyOptions& options);

}  // namespace springy

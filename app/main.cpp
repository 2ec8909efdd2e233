// springy: the command line.
#include <CLI/CLI.hpp>
#include <iostream>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "sim/error.h"
#include "sim/limits.h"

namespace {

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

void addRunOverrides(CLI::App* cmd, springy::RunOverrides& o) {
  cmd->add_option("--integrator", o.integrator, "Override the scene's integrator: " + springy::integratorNames());
  cmd->add_option("--dt", o.dt, "Override the scene's time step [s]");
  cmd->add_option_function<std::string>(
      "--substeps",
      [&o](const std::string& text) {
        if (text == "auto") {
          o.autoSubsteps = true;
          return;
        }
        std::size_t used = 0;
        int n = 0;
        try {
          n = std::stoi(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != text.size() || n < 1 || n > springy::kMaxSubsteps) {
          throw CLI::ValidationError("--substeps", "expected a whole number from 1 to " +
                                                       std::to_string(springy::kMaxSubsteps) + " or 'auto', got '" +
                                                       text + "'");
        }
        o.substeps = n;
      },
      "Steps of dt/N per dt, or 'auto': the stability advisor's safe number");
  cmd->add_option("--duration", o.duration, "Override the simulated duration [s]");
  cmd->add_option("--threads", o.threads,
                  "Simulation threads (default: $SPRINGY_THREADS, else all cores; models under " +
                      std::to_string(springy::World::kMinVerticesPerThread) +
                      " vertices per thread use fewer). Results are identical for every count.")
      ->check(CLI::Range(1u, 256u));
}

#ifdef SPRINGY_HAVE_RENDER
void addRenderOverrides(CLI::App* cmd, springy::RenderOverrides& o) {
  cmd->add_option("--width", o.width, "Frame width in pixels (even)");
  cmd->add_option("--height", o.height, "Frame height in pixels (even)");
  cmd->add_option("--fps", o.fps, "Frames per second");
  cmd->add_flag("--no-overlay", o.noOverlay, "No text overlay");
  cmd->add_flag("--no-shadows", o.noShadows, "No shadow pass");
  cmd->add_flag("--no-antialias", o.noAntialias, "No multisampling");
}
#endif

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"springy: soft bodies as springy meshes, simulated and rendered offscreen"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "springy 0.1");

  springy::CheckOptions check;
  CLI::App* checkCmd = app.add_subcommand("check", "Run scenes headlessly and check stability; per-body report");
  checkCmd->add_option("scenes", check.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  addRunOverrides(checkCmd, check.overrides);
  checkCmd->add_option("--trace", check.trace, "Write per-frame centroid, volume and energies as CSV");
  checkCmd->add_option("--min-volume", check.minVolume, "Fail if a body's volume falls below this fraction of rest")
      ->check(kFraction);
  checkCmd->add_option("--end-volume", check.endVolume, "Fail if a body ends below this fraction of its rest volume")
      ->check(kFraction);
  checkCmd->add_flag("--end-at-rest", check.endAtRest,
                     "Fail unless every body is at rest: over the last second no vertex moves more than 0.2% of "
                     "its body's size");

  springy::SuggestOptions suggest;
  CLI::App* suggestCmd =
      app.add_subcommand("suggest", "Estimate stable dt and propose stable T, P, T_theta, P_theta for a scene");
  suggestCmd->add_option("scenes", suggest.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  addRunOverrides(suggestCmd, suggest.overrides);
  suggestCmd
      ->add_option("--keep-volume", suggest.keepVolume,
                   "Volume fraction each body should keep through its first impact; suggest simulates the scene "
                   "to predict the squash, and the periods that keep this much (default 0.85)")
      ->check(kFraction);

  springy::StudyOptions study;
  CLI::App* studyCmd = app.add_subcommand("study", "Work-precision (accuracy) or stability study of the integrators");
  studyCmd->add_option("kind", study.kind, "accuracy or stability")->required()->check(CLI::IsMember({"accuracy", "stability"}));
  studyCmd->add_option("-o,--output", study.output, "Output directory (CSV, Markdown, plots)")->capture_default_str();
  studyCmd->add_option("--scenes", study.scenes, "Showcase scenes for the accuracy study (default: scenes/*.toml)")
      ->check(CLI::ExistingFile);
  studyCmd->add_flag("--quick", study.quick, "Small cases and few repeats (seconds; for tests and CI)");
  studyCmd->add_option("--repeats", study.repeats, "Timed runs per point (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));

#ifdef SPRINGY_HAVE_RENDER
  springy::RenderOptions render;
  CLI::App* renderCmd = app.add_subcommand("render", "Simulate scenes and encode MP4 videos (H.264)");
  renderCmd->add_option("scenes", render.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  renderCmd->add_option("-o,--output", render.output,
                        "Output .mp4 for one scene, or a directory (default: SCENE.mp4 here)");
  addRunOverrides(renderCmd, render.overrides);
  addRenderOverrides(renderCmd, render.render);
  renderCmd->add_option("--crf", render.render.crf, "H.264 quality, 0-51, lower is better");
  renderCmd->add_option("--preset", render.render.preset, "x264 preset (ultrafast ... veryslow)");

  springy::FramesOptions frames;
  CLI::App* framesCmd = app.add_subcommand("frames", "Write PNG stills at chosen times, and a contact sheet");
  framesCmd->add_option("scenes", frames.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  framesCmd->add_option("-o,--output", frames.output, "Output directory")->capture_default_str();
  framesCmd->add_option("--times", frames.times, "Comma-separated times in seconds (default: 8 evenly spaced)");
  framesCmd->add_flag("--sheet", frames.sheet, "Also write SCENE_sheet.png, a labelled grid of the stills");
  framesCmd->add_flag("--sheet-only", frames.sheetOnly, "Write only the contact sheet");
  addRunOverrides(framesCmd, frames.overrides);
  addRenderOverrides(framesCmd, frames.render);
#endif

  springy::installInterruptHandler();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (checkCmd->parsed()) return springy::runCheck(check);
    if (suggestCmd->parsed()) return springy::runSuggest(suggest);
    if (studyCmd->parsed()) return springy::runStudy(study);
#ifdef SPRINGY_HAVE_RENDER
    if (renderCmd->parsed()) return springy::runRender(render);
    if (framesCmd->parsed()) return springy::runFrames(frames);
#endif
  } catch (const springy::Error& e) {
    std::cerr << "springy: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "springy: out of memory (the scene or its meshes are too large for this machine)\n";
    return 1;
  } catch (const std::exception& e) {
    // Not a user error springy foresaw (those are springy::Error): still a message and a clean
    // exit, never std::terminate's abort, so that temporary outputs are removed.
    std::cerr << "springy: unexpected error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

// springy app: loading a scene with command-line overrides and stepping it frame by frame
// under the stability monitor. Shared by `check`, `render` and `frames`.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "app/records.h"
#include "scene/scene.h"
#include "sim/monitor.h"

namespace springy {

struct RunOverrides {
  std::optional<std::string> integrator;
  std::optional<double> dt, duration;
  std::optional<double> tolerance;  // --tolerance: an adaptive integrator at this tolerance
  std::optional<int> substeps;
  std::optional<int> iterations;  // --iterations: vbd's sweeps per step
  bool autoSubsteps = false;  // --substeps auto: the stability advisor picks them
  std::optional<unsigned> threads;  // --threads (default: SPRINGY_THREADS, else every core)
  // --set KEY=VALUE: scene keys set before the scene is read (applySceneSettings).
  std::vector<std::string> sets;
};

// Sets scene keys in a scene file's TOML text before it is read, as `--set KEY=VALUE` does: KEY
// is a dotted path of tables ("environment.drag", "scene.duration"), where an array of tables
// takes an index ("body.0.mass": the first [[body]]) or stands for each of its tables
// ("body.mass": every body); VALUE is a TOML value (0.5, "rk4", true, [0, 2, 0]). Missing tables
// are created. Returns the scene; throws springy::Error naming the file and the setting (an
// error of the scene file itself keeps its own line).
SceneDesc loadSceneSetting(const std::string& path, const std::vector<std::string>& sets);

// Loads a scene and applies the overrides. Throws springy::Error. advise: run the stability
// advisor (warn on stderr when the step exceeds its estimate; pick --substeps auto) and print the
// bodies' notes; without it nothing is printed (a sweep validating its points).
// With `runIsTry` (check, render, frames), a default step is not tried first (adviseTimeStep);
// *runIsTry then says whether the step is such an untried default, for the caller to run as its
// try (and, if that run fails, to call retryDefaultStep).
SceneDesc loadSceneWith(const std::string& path, const RunOverrides& overrides, bool advise = true,
                        bool* runIsTry = nullptr);

// The scene's world, stepping on the requested threads (World::setThreads: small models stay
// on one; results are bit-identical for every count). Throws springy::Error for a bad
// SPRINGY_THREADS.
World makeWorld(const SceneDesc& scene, const RunOverrides& overrides);

// The simulation threads the overrides ask for: --threads, else defaultThreadCount().
unsigned threadCount(const RunOverrides& overrides);

// "1 substep", "3 substeps": a count of substeps as the messages say it.
std::string substepsText(int count);

// Steps `world` until `time` (within half a step; the adaptive step lands on it), checking the
// monitor after the last step (and reporting an adaptive step that cannot meet its tolerance).
// Returns the failure, if any. Stops early, with nothing to report, when interrupted() (a
// signal): the caller sees the flag and stops.
std::optional<Failure> advanceTo(World& world, Monitor& monitor, double time);

// One body's results after a run (check's table, --json, the Python module's sim.check()):
// the monitor's extremes and last measures, and whether `rest` saw it at rest.
BodyResult bodyResult(const World& world, const Monitor& monitor, const RestWatch& rest, uint32_t body);

// How many of the body's vertices touch a collider or a body now (World::touching).
uint32_t touchingVertices(const World& world, uint32_t body);

// check's criteria at the end of a run that passed the monitor: --end-volume (a body ending
// below that fraction of its rest volume; 0: not checked) and --end-at-rest (every body at rest
// over the frames `rest` watched). The first failure (Failure::criterion set), if any.
std::optional<Failure> endCriteria(const World& world, const Monitor& monitor, const RestWatch& rest,
                                   double endVolume, bool endAtRest);

}  // namespace springy

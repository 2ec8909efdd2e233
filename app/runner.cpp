#include "app/runner.h"

#include <cmath>
#include <iostream>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "sim/error.h"
#include "sim/limits.h"
#include "sim/parallel.h"

namespace springy {

SceneDesc loadSceneWith(const std::string& path, const RunOverrides& overrides, bool advise) {
  SceneDesc scene = loadScene(path);
  for (const BodyDesc& b : scene.bodies) {
    if (!b.note.empty()) std::cerr << "springy: " << b.source << ": body '" << b.name << "': " << b.note << "\n";
  }
  if (overrides.integrator && !parseIntegrator(*overrides.integrator, scene.integrator)) {
    throw Error("--integrator: '" + *overrides.integrator + "' is not one of: " + integratorNames());
  }
  if (overrides.dt) {
    if (!(*overrides.dt > 0.0) || !std::isfinite(*overrides.dt)) throw Error("--dt must be a positive finite number of seconds");
    scene.dt = *overrides.dt;
  }
  if (overrides.duration) {
    if (!(*overrides.duration > 0.0) || !std::isfinite(*overrides.duration)) {
      throw Error("--duration must be a positive finite number of seconds");
    }
    scene.duration = *overrides.duration;
  }
  if (overrides.substeps) {
    if (*overrides.substeps < 1 || *overrides.substeps > kMaxSubsteps) {
      throw Error("--substeps must be between 1 and " + std::to_string(kMaxSubsteps) + " (or auto)");
    }
    scene.substeps = *overrides.substeps;
  }
  if (advise) {
    const StepChoice choice = overrides.autoSubsteps ? StepChoice::AutoSubsteps
                              : !scene.stepGiven && !overrides.dt && !overrides.substeps ? StepChoice::Default
                                                                                         : StepChoice::Warn;
    adviseTimeStep(path, scene, choice, std::cerr);
  }
  if (auto problem = runSettingsProblem(scene)) {
    throw Error(path + ": with the command line's settings, " + *problem);
  }
  return scene;
}

World makeWorld(const SceneDesc& scene, const RunOverrides& overrides) {
  World world(buildModel(scene), scene.integrator, stepSize(scene));
  world.setThreads(overrides.threads ? *overrides.threads : defaultThreadCount());
  return world;
}

std::optional<Failure> advanceTo(World& world, Monitor& monitor, double time) {
  while (world.time() < time - 0.5 * world.dt()) {
    // Polled every step, so that a long frame (a fine step, a large model) stops at once.
    if (interrupted()) return std::nullopt;
    world.step();
  }
  return monitor.check(world);
}

}  // namespace springy

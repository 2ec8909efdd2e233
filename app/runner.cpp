#include "app/runner.h"

#include <iostream>

#include "app/commands.h"
#include "sim/error.h"
#include "sim/parallel.h"

namespace springy {

SceneDesc loadSceneWith(const std::string& path, const RunOverrides& overrides, bool advise) {
  SceneDesc scene = loadScene(path);
  if (overrides.integrator && !parseIntegrator(*overrides.integrator, scene.integrator)) {
    throw Error("--integrator: '" + *overrides.integrator + "' is not one of: " + integratorNames());
  }
  if (overrides.dt) {
    if (!(*overrides.dt > 0.0)) throw Error("--dt must be positive");
    scene.dt = *overrides.dt;
  }
  if (overrides.duration) {
    if (!(*overrides.duration > 0.0)) throw Error("--duration must be positive");
    scene.duration = *overrides.duration;
  }
  if (overrides.substeps) {
    if (*overrides.substeps < 1) throw Error("--substeps must be at least 1");
    scene.substeps = *overrides.substeps;
  }
  if (advise) adviseTimeStep(path, scene, overrides.autoSubsteps, std::cerr);
  return scene;
}

World makeWorld(const SceneDesc& scene, const RunOverrides& overrides) {
  World world(buildModel(scene), scene.integrator, stepSize(scene));
  world.setThreads(overrides.threads ? *overrides.threads : defaultThreadCount());
  return world;
}

std::optional<Failure> advanceTo(World& world, Monitor& monitor, double time) {
  while (world.time() < time - 0.5 * world.dt()) world.step();
  return monitor.check(world);
}

}  // namespace springy

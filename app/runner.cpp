#include "app/runner.h"

#include <toml++/toml.h>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "sim/error.h"
#include "sim/limits.h"
#include "sim/parallel.h"

namespace springy {

namespace {

// Sets `value` at parts[i..] below `node` (applySceneSettings). `setting` names it in errors.
void setKey(toml::node& node, const std::vector<std::string>& parts, std::size_t i, const toml::node& value,
            const std::string& setting) {
  const std::string& part = parts[i];
  if (toml::array* array = node.as_array()) {
    if (!array->is_array_of_tables() || array->empty()) {
      throw Error("--set " + setting + ": '" + parts[i - 1] + "' is not an array of tables ([[" + parts[i - 1] + "]])");
    }
    const bool index = !part.empty() && part.find_first_not_of("0123456789") == std::string::npos;
    if (!index) {  // every table of the array
      for (toml::node& each : *array) setKey(each, parts, i, value, setting);
      return;
    }
    const std::size_t k = part.size() > 6 ? array->size() : std::stoul(part);
    if (k >= array->size()) {
      throw Error("--set " + setting + ": the scene has " + std::to_string(array->size()) + " [[" + parts[i - 1] +
                  "]] (indices from 0)");
    }
    if (i + 1 == parts.size()) throw Error("--set " + setting + ": names a whole table, not a key");
    setKey(*array->get(k), parts, i + 1, value, setting);
    return;
  }
  toml::table* table = node.as_table();
  if (!table) throw Error("--set " + setting + ": '" + parts[i - 1] + "' is a value, not a table");
  if (i + 1 == parts.size()) {
    value.visit([&](const auto& v) { table->insert_or_assign(part, v); });
    return;
  }
  if (!table->contains(part)) table->insert(part, toml::table{});
  setKey(*table->get(part), parts, i + 1, value, setting);
}

void applySetting(toml::table& root, const std::string& setting) {
  const std::size_t equals = setting.find('=');
  if (equals == std::string::npos) throw Error("--set " + setting + ": expected KEY=VALUE");
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const std::size_t dot = std::min(setting.find('.', start), equals);
    parts.push_back(setting.substr(start, dot - start));
    if (parts.back().empty()) throw Error("--set " + setting + ": an empty key in '" + setting.substr(0, equals) + "'");
    if (dot == equals) break;
    start = dot + 1;
  }
  toml::table parsed;
  try {
    parsed = toml::parse("value = " + setting.substr(equals + 1));
  } catch (const toml::parse_error&) {
    throw Error("--set " + setting +
                ": the value is not a TOML value (a number, a \"string\", true or false, an [array])");
  }
  setKey(root, parts, 0, *parsed.get("value"), setting);
}

// The scene error `message` without its "PATH:LINE:COLUMN: " prefix.
std::string withoutLocation(const std::string& message, const std::string& path) {
  if (message.rfind(path + ":", 0) != 0) return message;
  std::size_t at = path.size() + 1;
  for (int field = 0; field < 2; ++field) {  // line, column
    const std::size_t colon = message.find(':', at);
    if (colon == std::string::npos || message.find_first_not_of("0123456789", at) != colon) return message;
    at = colon + 1;
  }
  return message.substr(message[at] == ' ' ? at + 1 : at);
}

}  // namespace

SceneDesc loadSceneSetting(const std::string& path, const std::vector<std::string>& sets) {
  if (sets.empty()) return loadScene(path);
  checkInputFile(path, kMaxSceneFileBytes, "scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the scene file");
  std::ostringstream text;
  text << in.rdbuf();
  toml::table root;
  try {
    root = toml::parse(text.str(), path);
  } catch (const toml::parse_error&) {
    return parseScene(text.str(), path);  // throws the scene's own error, with its line
  }
  for (const std::string& setting : sets) applySetting(root, setting);
  std::ostringstream changed;  // floats are written with every digit: the same numbers read back
  changed << toml::toml_formatter(root);
  try {
    return parseScene(changed.str(), path);
  } catch (const Error& e) {
    parseScene(text.str(), path);  // an error in the file itself is reported at its own line
    std::string all;
    for (const std::string& setting : sets) all += (all.empty() ? "" : ", ") + setting;
    throw Error(path + ": with --set " + all + ": " + withoutLocation(e.what(), path));
  }
}

SceneDesc loadSceneWith(const std::string& path, const RunOverrides& overrides, bool advise, bool* runIsTry) {
  SceneDesc scene = loadSceneSetting(path, overrides.sets);
  for (const BodyDesc& b : scene.bodies) {
    if (advise && !b.note.empty()) {
      std::cerr << "springy: " << b.source << ": body '" << b.name << "': " << b.note << "\n";
    }
  }
  if (overrides.integrator && !parseIntegrator(*overrides.integrator, scene.integrator)) {
    throw Error("--integrator: '" + *overrides.integrator + "' is not one of: " + integratorNames());
  }
  if (overrides.tolerance) {
    if (!(*overrides.tolerance >= 1e-12 && *overrides.tolerance <= 0.5)) {
      throw Error("--tolerance must be a number from 1e-12 to 0.5 (a fraction of each body's size)");
    }
    if (overrides.integrator && !isAdaptive(scene.integrator)) {
      throw Error("--tolerance needs an adaptive integrator (bs32, verlet_adaptive), not --integrator " +
                  *overrides.integrator);
    }
    scene.tolerance = *overrides.tolerance;
    if (!isAdaptive(scene.integrator)) scene.integrator = kDefaultAdaptive;
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
  if (overrides.iterations) {
    if (*overrides.iterations < 1 || *overrides.iterations > kMaxIterations) {
      throw Error("--iterations must be between 1 and " + std::to_string(kMaxIterations));
    }
    if (scene.integrator != Integrator::Vbd) {
      throw Error("--iterations sets vbd's sweeps a step, but the run's integrator is " +
                  std::string(integratorName(scene.integrator)) + " (add --integrator vbd)");
    }
    scene.iterations = *overrides.iterations;
  }
  if (overrides.substeps) {
    if (*overrides.substeps < 1 || *overrides.substeps > kMaxSubsteps) {
      throw Error("--substeps must be between 1 and " + std::to_string(kMaxSubsteps) + " (or auto)");
    }
    scene.substeps = *overrides.substeps;
  }
  if (advise && !isAdaptive(scene.integrator)) {  // the adaptive step needs no advice
    const StepChoice choice = overrides.autoSubsteps ? StepChoice::AutoSubsteps
                              : !scene.stepGiven && !overrides.dt && !overrides.substeps ? StepChoice::Default
                                                                                         : StepChoice::Warn;
    const bool deferred = runIsTry != nullptr && choice == StepChoice::Default;
    adviseTimeStep(path, scene, choice, threadCount(overrides), std::cerr, deferred);
    if (runIsTry) *runIsTry = deferred;
  }
  if (auto problem = runSettingsProblem(scene)) {
    throw Error(path + ": with the command line's settings, " + *problem);
  }
  return scene;
}

unsigned threadCount(const RunOverrides& overrides) {
  return overrides.threads ? *overrides.threads : defaultThreadCount();
}

std::string substepsText(int count) { return std::to_string(count) + (count == 1 ? " substep" : " substeps"); }

World makeWorld(const SceneDesc& scene, const RunOverrides& overrides) {
  World world(buildModel(scene), scene.integrator, stepSize(scene));
  if (world.adaptive()) world.setTolerance(scene.tolerance);
  world.setIterations(scene.iterations);
  world.setThreads(threadCount(overrides));
  return world;
}

std::optional<Failure> advanceTo(World& world, Monitor& monitor, double time) {
  while (!world.reached(time)) {
    // Polled every step, so that a long frame (a fine step, a large model) stops at once.
    if (interrupted()) return std::nullopt;
    world.stepToward(time);
    if (!world.stepProblem().empty()) {
      std::optional<Failure> failure = monitor.check(world);  // a blow-up it sees says more
      if (failure) return failure;
      return Failure{0, world.stepCount(), world.time(), world.stepProblem()};
    }
  }
  return monitor.check(world);
}

BodyResult bodyResult(const World& world, const Monitor& monitor, const RestWatch& rest, uint32_t body) {
  const BodyRecord& r = monitor.records()[body];
  const BodyInfo& info = world.model().bodies[body];
  BodyResult result;
  result.name = info.name;
  result.steps = world.stepCount();
  result.time = world.time();
  result.maxStrain = r.maxStrain;
  result.maxPenetration = r.maxPenetration;
  if (info.restVolume > 0.0) {  // an open surface (a cloth) encloses no volume
    result.volumeMin = r.minVolumeRatio;
    result.volumeEnd = r.last.volume / info.restVolume;
  }
  result.kinetic = r.last.kinetic;
  result.gravitational = r.last.gravitational;
  result.elastic = r.last.elastic;
  result.atRest = rest.atRest(info);
  return result;
}

std::optional<Failure> endCriteria(const World& world, const Monitor& monitor, const RestWatch& rest,
                                   double endVolume, bool endAtRest) {
  const std::vector<BodyInfo>& bodies = world.model().bodies;
  for (uint32_t b = 0; b < bodies.size() && endVolume > 0.0; ++b) {
    const BodyInfo& info = bodies[b];
    if (!(info.restVolume > 0.0)) continue;  // an open surface: no volume to keep
    const double ratio = monitor.records()[b].last.volume / info.restVolume;
    if (ratio < endVolume) {
      char what[256];
      std::snprintf(what, sizeof what, "body '%s' ends at %.1f%% of its rest volume, below the required %.1f%%",
                    info.name.c_str(), 100.0 * ratio, 100.0 * endVolume);
      return Failure{b, world.stepCount(), world.time(), what, true};
    }
  }
  for (uint32_t b = 0; b < bodies.size() && endAtRest; ++b) {
    const BodyInfo& info = bodies[b];
    if (rest.atRest(info)) continue;
    const auto [moved, worst] = rest.largestMove(info);
    char what[400];
    std::snprintf(what, sizeof what,
                  "body '%s' is not at rest at the end: in the last %.0f s its vertex %u (of the mesh) moved "
                  "over %.3g m, more than %.3g m (%.1f%% of its size); lengthen the scene or damp the body more "
                  "(strut_decay, hinge_decay, [environment] drag)",
                  info.name.c_str(), RestWatch::kWindow, info.meshVertex(worst), moved,
                  RestWatch::kFraction * info.restSize, 100.0 * RestWatch::kFraction);
    return Failure{b, world.stepCount(), world.time(), what, true};
  }
  return std::nullopt;
}

uint32_t touchingVertices(const World& world, uint32_t body) {
  const BodyInfo& info = world.model().bodies[body];
  uint32_t count = 0;
  for (uint32_t v = info.firstVertex; v < info.firstVertex + info.vertexCount; ++v) count += world.touching(v) ? 1 : 0;
  return count;
}

}  // namespace springy

#include "run/load.h"

#include <toml++/toml.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "run/advisor.h"
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

std::vector<std::string> sceneInputFiles(const std::string& path, const std::vector<std::string>& sets) {
  try {
    checkInputFile(path, kMaxSceneFileBytes, "scene file");
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (sets.empty()) return sceneInputs(text.str(), path);
    toml::table root = toml::parse(text.str(), path);
    for (const std::string& setting : sets) applySetting(root, setting);
    std::ostringstream changed;
    changed << toml::toml_formatter(root);
    return sceneInputs(changed.str(), path);
  } catch (const std::exception&) {  // Error, toml::parse_error: reported when the scene is loaded
    return {path};
  }
}

std::vector<std::string> sceneInputFiles(const std::vector<std::string>& paths, const std::vector<std::string>& sets) {
  std::vector<std::string> out;
  for (const std::string& path : paths) {
    for (std::string& file : sceneInputFiles(path, sets)) {
      if (std::find(out.begin(), out.end(), file) == out.end()) out.push_back(std::move(file));
    }
  }
  return out;
}

SceneDesc loadSceneWith(const std::string& path, const RunOptions& options, bool advise, bool* runIsTry) {
  checkRunOptions(options);
  SceneDesc scene = loadSceneSetting(path, options.sets);
  for (const BodyDesc& b : scene.bodies) {
    if (advise && !b.note.empty()) {
      std::cerr << "springy: " << b.source << ": body '" << b.name << "': " << b.note << "\n";
    }
  }
  if (options.integrator) parseIntegrator(*options.integrator, scene.integrator);
  if (options.tolerance) {
    if (options.integrator && !isAdaptive(scene.integrator)) {
      throw Error("--tolerance needs an adaptive integrator (bs32, verlet_adaptive), not --integrator " +
                  *options.integrator);
    }
    scene.tolerance = *options.tolerance;
    if (!isAdaptive(scene.integrator)) scene.integrator = kDefaultAdaptive;
  }
  if (options.dt) scene.dt = *options.dt;
  if (options.duration) scene.duration = *options.duration;
  if (options.iterations) {
    if (!integratorTraits(scene.integrator).takesIterations) {
      throw Error("--iterations sets vbd's sweeps a step, but the run's integrator is " +
                  std::string(integratorName(scene.integrator)) + " (add --integrator vbd)");
    }
    scene.iterations = *options.iterations;
  }
  if (options.substeps) scene.substeps = *options.substeps;
  if (advise && !isAdaptive(scene.integrator)) {  // the adaptive step needs no advice
    const StepChoice choice = options.autoSubsteps ? StepChoice::AutoSubsteps
                              : !scene.stepGiven && !options.dt && !options.substeps ? StepChoice::Default
                                                                                         : StepChoice::Warn;
    const bool deferred = runIsTry != nullptr && choice == StepChoice::Default;
    adviseTimeStep(path, scene, choice, threadCount(options), std::cerr, deferred);
    if (runIsTry) *runIsTry = deferred;
  }
  if (auto problem = runSettingsProblem(scene)) {
    throw Error(path + ": with the command line's settings, " + *problem);
  }
  return scene;
}

World makeWorld(const SceneDesc& scene, const RunOptions& options) {
  World world(buildModel(scene), scene.integrator, stepSize(scene));
  if (world.adaptive()) world.setTolerance(scene.tolerance);
  world.setIterations(scene.iterations);
  world.setThreads(threadCount(options));
  return world;
}

}  // namespace springy

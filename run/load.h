// springy run: a scene loaded for a run. The scene file with --set's keys set first, the run
// options over the scene's own settings, and the time step: the scene's, the options', or the
// advisor's (run/advisor.h) where neither gives one.
#pragma once

#include <string>
#include <vector>

#include "run/options.h"
#include "scene/scene.h"
#include "sim/world.h"

namespace springy {

// Sets scene keys in a scene file's TOML text before it is read, as `--set KEY=VALUE` does: KEY
// is a dotted path of tables ("environment.drag", "scene.duration"), where an array of tables
// takes an index ("body.0.mass": the first [[body]]) or stands for each of its tables
// ("body.mass": every body); VALUE is a TOML value (0.5, "rk4", true, [0, 2, 0]). Missing tables
// are created. Returns the scene; throws springy::Error naming the file and the setting (an
// error of the scene file itself keeps its own line).
SceneDesc loadSceneSetting(const std::string& path, const std::vector<std::string>& sets);

// The files the scene at `path` reads with `sets` applied (scene/scene.h sceneInputs), without
// loading it: what a command's outputs are checked against before any run. A scene that cannot
// be read gives {path} (its error comes when it is loaded).
std::vector<std::string> sceneInputFiles(const std::string& path, const std::vector<std::string>& sets);
// The same for every scene of a command, each file once.
std::vector<std::string> sceneInputFiles(const std::vector<std::string>& paths, const std::vector<std::string>& sets);

// Loads a scene and applies the options. Throws springy::Error. advise: run the stability
// advisor (warn on stderr when the step exceeds its estimate; pick --substeps auto) and print the
// bodies' notes; without it nothing is printed (a sweep validating its points).
// With `runIsTry` (a Run), a default step is not tried first (adviseTimeStep); *runIsTry then says
// whether the step is such an untried default, for the caller to run as its try (and, if that run
// fails, to call retryDefaultStep).
SceneDesc loadSceneWith(const std::string& path, const RunOptions& options, bool advise = true,
                        bool* runIsTry = nullptr);

// The scene's world, stepping on the requested threads (World::setThreads: small models stay
// on one; results are bit-identical for every count). Throws springy::Error for a bad
// SPRINGY_THREADS.
World makeWorld(const SceneDesc& scene, const RunOptions& options);

}  // namespace springy

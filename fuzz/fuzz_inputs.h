// springy: what the fuzz targets (fuzz/) and the regression test (tests/test_fuzz_regressions.cpp)
// do with one input, shared so that a reproducer runs the same code in both.
//
// Any springy::Error is an expected outcome (the input is rejected with a message); every other
// exception, crash, sanitizer report, leak, timeout or runaway allocation is a bug.
#pragma once

#include <pthread.h>

#include <algorithm>
#include <csignal>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "run/load.h"
#include "scene/scene.h"
#include "sim/error.h"
#include "mesh/mesh_io.h"
#include "sim/model.h"
#include "sim/world.h"

namespace springy::fuzz {

// readMeshFile may run assimp in a forked child process that turns a crash there into an Error.
// The child inherits libFuzzer's and the sanitizers' signal handlers, which would report that
// contained crash as the fuzzer's own (and write a crash file); so every forked child gets the
// default actions back. A sanitizer report from instrumented code in the child (springy's code)
// does not go through these signals and is still reported.
inline void defaultCrashSignalsInForkedChildren() {
  static const bool installed = [] {
    pthread_atfork(nullptr, nullptr, [] {
      for (int s : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL, SIGALRM}) std::signal(s, SIG_DFL);
    });
    return true;
  }();
  (void)installed;
}

// Where a fuzzed scene claims to live: mesh paths in it resolve against the repository's
// scenes/ directory, so that `mesh = "assets/bunny.ply"` (from the seed corpus) loads a real mesh.
inline std::string scenePath(const std::string& sourceDir) { return sourceDir + "/scenes/fuzz-input.toml"; }

// buildModel's cost grows with the scene's size, which a legitimate scene may make large (a
// 256-subdivision sphere has 262k vertices; all_pairs has a strut per vertex pair). The fuzzer
// would report that as a timeout, so the model is built only for scenes below these limits.
constexpr std::size_t kMaxBuildVertices = 200000;
constexpr std::size_t kMaxBuildAllPairsStruts = 2000000;

inline bool worthBuilding(const SceneDesc& scene) {
  std::size_t vertices = 0, allPairsStruts = 0;
  for (const BodyDesc& b : scene.bodies) {
    const std::size_t n = b.mesh.positions.size();
    vertices += n;
    if (b.model == SpringModel::AllPairs) allPairsStruts += n * (n - 1) / 2;
  }
  return vertices <= kMaxBuildVertices && allPairsStruts <= kMaxBuildAllPairsStruts;
}

// parseScene, then buildModel when the scene is not too large. Returns false when an Error
// rejected the input.
inline bool runScene(const std::string& text, const std::string& path) {
  try {
    const SceneDesc scene = parseScene(text, path);
    if (worthBuilding(scene)) buildModel(scene);
    return true;
  } catch (const Error&) {
    return false;
  }
}

// The motion target's input is a scene file's text, as the scene target's; the scene is then run
// for a few steps, so that what moves on its own (motion tables of planes, [[triangles]] and
// props, pin_motion and pin_release, [[attach]] springs and their release) is evaluated and
// stepped, not only read. Stepping costs more than building, so the limits are lower; a scene
// whose solver iterations alone would pass the fuzzer's time limit is only built.
constexpr std::size_t kMaxStepVertices = 20000;
constexpr int kMaxStepIterations = 200;
constexpr int kMotionSteps = 24;

inline bool worthStepping(const SceneDesc& scene) {
  std::size_t vertices = 0;
  for (const BodyDesc& b : scene.bodies) vertices += b.mesh.positions.size();
  return worthBuilding(scene) && vertices <= kMaxStepVertices && scene.iterations <= kMaxStepIterations;
}

// parseScene, makeWorld (one thread) and kMotionSteps steps of the scene's step. Returns false
// when an Error rejected the input (a refusal while stepping included). A state that goes
// non-finite is the monitor's to catch (not here): only a crash or a sanitizer report is a bug.
inline bool runSceneSteps(const std::string& text, const std::string& path) {
  try {
    const SceneDesc scene = parseScene(text, path);
    if (!worthBuilding(scene)) return true;
    if (!worthStepping(scene)) {
      buildModel(scene);
      return true;
    }
    RunOptions options;
    options.threads = 1;
    World world = makeWorld(scene, options);
    for (int i = 0; i < kMotionSteps; ++i) world.step();
    return true;
  } catch (const Error&) {
    return false;
  }
}

// The --set target's input: its first byte picks one of the repository's scenes (kSetScenes,
// byte mod their count), the rest is lines, each one `--set KEY=VALUE` as the command line takes
// it (loadSceneSetting, run/load.h), applied in order; the scene is then built as the scene
// target builds it. Append only: reordering would change what every corpus entry means.
constexpr std::string_view kSetScenes[] = {"single_sphere", "spheres", "press",  "cape",  "pile",
                                           "bunny_light",   "jelly",   "shaker", "drape", "stack"};
constexpr std::size_t kSetSceneCount = sizeof(kSetScenes) / sizeof(kSetScenes[0]);

inline std::string setScenePath(const std::string& sourceDir, uint8_t selector) {
  return sourceDir + "/scenes/" + std::string(kSetScenes[selector % kSetSceneCount]) + ".toml";
}

// The settings of a --set input: its lines after the first byte (empty lines kept: an empty
// setting is an input too).
inline std::vector<std::string> settingsOf(std::string_view text) {
  std::vector<std::string> sets;
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    sets.emplace_back(text.substr(start, end - start));
    start = end + 1;
  }
  return sets;
}

inline bool runSettings(const std::string& sourceDir, const uint8_t* data, std::size_t size) {
  if (size == 0) return true;
  try {
    const SceneDesc scene = loadSceneSetting(setScenePath(sourceDir, data[0]),
                                             settingsOf({reinterpret_cast<const char*>(data) + 1, size - 1}));
    if (worthBuilding(scene)) buildModel(scene);
    return true;
  } catch (const Error&) {
    return false;
  }
}

// The mesh target's input is one byte choosing the file's extension, then the file's bytes.
// Only formats assimp 5.2 (Debian 12) reads; assimp picks the reader by extension first, then by
// content. Append only: reordering would change what every corpus entry means.
constexpr std::string_view kMeshExtensions[] = {"ply", "obj", "stl", "off", "gltf",
                                                "glb", "3ds", "dae", "fbx"};
constexpr std::size_t kMeshExtensionCount = sizeof(kMeshExtensions) / sizeof(kMeshExtensions[0]);

inline std::string_view meshExtension(uint8_t selector) { return kMeshExtensions[selector % kMeshExtensionCount]; }

// The work done on one mesh file: what a [[triangles]] collider does (read, exact weld), what a
// [[body]] does (loadClosedMesh), and simplification of a closed mesh to half its vertices (the
// `simplify` key). Returns false when an Error rejected the file.
inline bool runMeshFile(const std::string& path) {
  constexpr std::size_t kMaxSimplifyVertices = 50000;
  try {
    const TriMesh raw = readMeshFile(path);
    weldVertices(raw, 0.0);
    const TriMesh closed = loadClosedMesh(path);
    if (closed.positions.size() <= kMaxSimplifyVertices) {
      simplifyMesh(closed, closed.positions.size() / 2 < 4 ? 4 : closed.positions.size() / 2);
    }
    return true;
  } catch (const Error&) {
    return false;
  }
}

}  // namespace springy::fuzz

// springy: the limits that keep a run's memory and time bounded, and what a file must be before
// springy reads it.
//
// Every file a user names (scene, body mesh, collider mesh) is checked before it is opened for
// reading: it must exist, be a regular file (not a directory, FIFO or device such as /dev/zero,
// which would block or never end) and be no larger than the limit for its kind. The counts that
// memory follows are bounded too, and checked before anything is allocated for them.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

namespace springy {

// Limits, documented in README.md ("Limits").
constexpr std::uintmax_t kMaxSceneFileBytes = 16u << 20;    // 16 MiB of TOML
constexpr std::uintmax_t kMaxMeshFileBytes = 256u << 20;    // 256 MiB per mesh file
constexpr std::uint64_t kMaxMeshVertices = 1u << 24;        // 16.7 M vertices per mesh file
constexpr std::uint64_t kMaxMeshTriangles = 1u << 25;       // 33.5 M triangles per mesh file
// A mesh file is parsed (by assimp) in a child process limited to this much time and memory: a
// corrupt file that crashes, hangs or floods the parser is an error, never springy's end. The
// memory grows with the file: 512 MiB and 32 bytes per byte of the file, at most 8 GiB (assimp
// reads a legitimate file in a few times its size; a corrupt 1 KiB COLLADA file found by the
// fuzzer made it allocate without end, 3 GiB in 7 s before the old fixed 8 GiB limit stopped it).
constexpr unsigned kMeshReadSeconds = 120;
constexpr std::uint64_t meshReadBytes(std::uintmax_t fileBytes) {
  const std::uint64_t most = 8ull << 30;
  return fileBytes >= (most >> 5) ? most : std::min<std::uint64_t>(most, (512ull << 20) + 32ull * fileBytes);
}
constexpr std::uint64_t kMaxSceneVertices = 1u << 22;       // 4.2 M vertices in all bodies (~2 GB of model)
constexpr std::uint64_t kMaxAllPairsVertices = 4096;        // model = "all_pairs": 8.4 M struts
constexpr double kMaxSteps = 1e9;                           // steps in one run (duration / (dt / substeps))
constexpr int kMaxSubsteps = 100000;
constexpr int kMaxIterations = 1000;  // vbd's sweeps per step ([scene] iterations, --iterations)
constexpr int kMaxProxyVertices = 1 << 16;                  // proxy_vertices (1 << 20 took 204 s to build)
constexpr std::size_t kMaxPinNear = 256;                    // pin_near points per body
constexpr int kMaxClothResolution = 512;                    // shape = "cloth": quads per side
// proxy = "auto" wraps a mesh of more vertices than this (far finer than a body needs).
constexpr std::size_t kProxyAutoMaxVertices = 20000;
// A proxy's default vertex count is the input's, clamped to 162 .. this (the body material behaves
// alike at every count, so a coarse proxy is as good a body and much faster).
constexpr std::size_t kProxyDefaultMaxVertices = 642;

// Ranges of body parameters that keep every derived constant finite and positive.
constexpr double kMinMass = 1e-9, kMaxMass = 1e9;           // [kg]
constexpr double kMinTime = 1e-6, kMaxTime = 1e6;           // periods and decay times [s]
constexpr double kMaxConstant = 1e15;                       // strut_stiffness etc. (SI units)

// Throws springy::Error "PATH: <what is wrong>" unless `path` names a readable regular file of at
// most maxBytes bytes (`what` names the kind: "scene file", "mesh file"). Returns its size.
std::uintmax_t checkInputFile(const std::string& path, std::uintmax_t maxBytes, const char* what);

}  // namespace springy

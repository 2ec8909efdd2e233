// springy: an indexed triangle mesh, the common currency between shape generators, mesh
// import, validation, the simulation and the app's draw data.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "sim/vec3.h"

namespace springy {

using Triangle = std::array<uint32_t, 3>;

struct TriMesh {
  std::vector<Vec3> positions;      // [m]
  std::vector<Triangle> triangles;  // counter-clockwise seen from outside (outward normals)
};

// Signed volume enclosed by a closed mesh (divergence theorem); positive when outward-oriented.
double signedVolume(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles);

// Axis-aligned bounds of a point set.
struct Bounds {
  Vec3 lo, hi;
  Vec3 size() const { return hi - lo; }
  Vec3 center() const { return (lo + hi) * 0.5; }
};
Bounds boundsOf(const std::vector<Vec3>& positions);

}  // namespace springy

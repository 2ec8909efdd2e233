// springy: a render mesh embedded in a simulated surface.
//
// When a body is simulated through a proxy (mesh/proxy.h), what the video shows is still the mesh
// the user gave, whatever its topology (holes, pieces, its own vertex count): each of its
// vertices is bound once, at rest, to the nearest triangle of the simulated surface, with
// coordinates in that triangle's frame, and is placed from the triangle's corners every frame
// (as Bullet's interpolateRenderMesh and game cloth proxies do).
//
// The frame of triangle (p0, p1, p2) is e1 = p1 - p0, e2 = p2 - p0 and the unit normal n; a bound
// vertex is x = p0 + u e1 + v e2 + h n. At rest this gives the input back to rounding (the three
// coordinates solve that 3x3 system exactly); under a rigid motion of the surface the frame moves
// rigidly and so does the drawn mesh; when the triangle stretches or shears, its bound vertices
// follow it affinely, and along its normal by their distance h. Vertices bound to neighbouring
// triangles follow different frames, so a sharply folded surface shows the fold in the drawn mesh
// as a crease; the drawn mesh stays connected (its own topology is kept).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "sim/mesh.h"

namespace springy {

struct Embedding {
  std::vector<Triangle> corners;              // per bound vertex: the surface triangle's corners
  std::vector<std::array<double, 3>> coords;  // per bound vertex: (u, v, h)

  std::size_t size() const { return corners.size(); }
  bool empty() const { return corners.empty(); }
};

// Binds every point to the surface triangle nearest to it (a bounding-volume search; ties go to
// the lowest triangle, so the binding is deterministic).
Embedding bindToSurface(const TriMesh& surface, const std::vector<Vec3>& points);

// Places the bound vertices from the surface's vertex positions `xyz` (x, y, z per vertex, indexed
// as the embedding's corners): out gets x, y, z per bound vertex. T is float (drawing) or double.
template <typename T>
void placeEmbedded(const Embedding& e, const T* xyz, T* out) {
  for (std::size_t k = 0; k < e.corners.size(); ++k) {
    const T* p0 = xyz + 3 * e.corners[k][0];
    const T* p1 = xyz + 3 * e.corners[k][1];
    const T* p2 = xyz + 3 * e.corners[k][2];
    const T e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const T e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    T n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const T len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const T inv = len > T(0) ? T(1) / len : T(0);  // a collapsed triangle: its plane only
    const T u = static_cast<T>(e.coords[k][0]), v = static_cast<T>(e.coords[k][1]);
    const T h = static_cast<T>(e.coords[k][2]) * inv;
    for (int a = 0; a < 3; ++a) out[3 * k + a] = p0[a] + u * e1[a] + v * e2[a] + h * n[a];
  }
}

}  // namespace springy

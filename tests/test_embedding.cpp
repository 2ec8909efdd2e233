// A render mesh embedded in a simulated surface (sim/embedding.h): exact at rest, rigid under a
// rigid motion, affine with its triangle when the surface deforms.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/embedding.h"
#include "mesh/proxy.h"
#include "sim/shapes.h"

namespace springy {
namespace {

std::vector<double> flat(const std::vector<Vec3>& points) {
  std::vector<double> xyz;
  for (const Vec3& p : points) xyz.insert(xyz.end(), {p.x, p.y, p.z});
  return xyz;
}

// A UV sphere with pole fans (the usual mesh from elsewhere), not closed at its seam: the drawn
// mesh; and its proxy at about 400 vertices: the simulated surface.
struct Embedded {
  TriMesh drawn, proxy;
  Embedding binding;
};
Embedded makeSetup() {
  Embedded s;
  const int rings = 24, segments = 48;
  for (int r = 0; r <= rings; ++r) {
    const double theta = kPi * r / rings;
    for (int k = 0; k < segments; ++k) {
      const double phi = 2 * kPi * k / segments;
      s.drawn.positions.push_back({std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)});
    }
  }
  for (int r = 0; r < rings; ++r) {
    for (int k = 0; k + 1 < segments; ++k) {  // the last column left open: a seam
      const uint32_t a = static_cast<uint32_t>(r * segments + k), b = a + 1, c = a + segments, d = c + 1;
      s.drawn.triangles.push_back({a, c, b});
      s.drawn.triangles.push_back({b, c, d});
    }
  }
  ProxyOptions options;
  options.targetVertices = 400;
  s.proxy = buildProxy(s.drawn, options).mesh;
  s.binding = bindToSurface(s.proxy, s.drawn.positions);
  return s;
}

TEST(Embedding, AtRestTheDrawnMeshIsTheInput) {
  const Embedded s = makeSetup();
  ASSERT_EQ(s.binding.size(), s.drawn.positions.size());
  const std::vector<double> x = flat(s.proxy.positions);
  std::vector<double> out(3 * s.binding.size());
  placeEmbedded(s.binding, x.data(), out.data());
  double worst = 0.0;
  for (std::size_t i = 0; i < s.drawn.positions.size(); ++i) {
    worst = std::max(worst, length(Vec3{out[3 * i], out[3 * i + 1], out[3 * i + 2]} - s.drawn.positions[i]));
  }
  EXPECT_LT(worst, 1e-6 * 2.0) << "size 2";  // within 1e-6 of the mesh's size
  // Each vertex is bound close to the surface (the wrap hugs the input).
  for (const auto& c : s.binding.coords) EXPECT_LT(std::fabs(c[2]), 0.1);
}

TEST(Embedding, UnderARigidMotionTheDrawnMeshMovesRigidly) {
  const Embedded s = makeSetup();
  // A rotation about an oblique axis and a translation.
  const Vec3 axis = normalized(Vec3{1, 2, 3});
  const double angle = 0.7;
  auto rigid = [&](const Vec3& p) {
    const Vec3 r = p * std::cos(angle) + cross(axis, p) * std::sin(angle) + axis * dot(axis, p) * (1 - std::cos(angle));
    return r + Vec3{4, -1, 2.5};
  };
  std::vector<Vec3> moved;
  for (const Vec3& p : s.proxy.positions) moved.push_back(rigid(p));
  const std::vector<double> x = flat(moved);
  std::vector<double> out(3 * s.binding.size());
  placeEmbedded(s.binding, x.data(), out.data());
  double worst = 0.0;
  for (std::size_t i = 0; i < s.drawn.positions.size(); ++i) {
    worst = std::max(worst, length(Vec3{out[3 * i], out[3 * i + 1], out[3 * i + 2]} - rigid(s.drawn.positions[i])));
  }
  EXPECT_LT(worst, 1e-12 * 10);
}

TEST(Embedding, AStretchedSurfaceStretchesTheDrawnMeshWithIt) {
  const Embedded s = makeSetup();
  // Scale the proxy by 1.5 along y: each triangle's frame follows, so a vertex on the surface
  // (h = 0 would be exact) lands at 1.5 y up to its small distance from the surface.
  std::vector<Vec3> stretched;
  for (const Vec3& p : s.proxy.positions) stretched.push_back({p.x, 1.5 * p.y, p.z});
  const std::vector<double> x = flat(stretched);
  std::vector<double> out(3 * s.binding.size());
  placeEmbedded(s.binding, x.data(), out.data());
  for (std::size_t i = 0; i < s.drawn.positions.size(); ++i) {
    const Vec3& p = s.drawn.positions[i];
    EXPECT_NEAR(out[3 * i + 1], 1.5 * p.y, 0.1) << i;
    EXPECT_NEAR(out[3 * i], p.x, 0.1) << i;
  }
}

TEST(Embedding, TheBindingIsDeterministic) {
  const Embedded a = makeSetup(), b = makeSetup();
  EXPECT_EQ(a.binding.corners, b.binding.corners);
  EXPECT_EQ(a.binding.coords, b.binding.coords);
}

}  // namespace
}  // namespace springy

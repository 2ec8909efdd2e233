// Tests for the simulation proxy (mesh/proxy.h): alpha wrapping + isotropic remeshing of bad
// meshes into closed, outward, manifold, well-shaped bodies, and needsProxy's verdicts.
#include <gtest/gtest.h>

#include "error_of.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sim/error.h"
#include "mesh/mesh_io.h"
#include "mesh/proxy.h"
#include "sim/shapes.h"

namespace springy {
namespace {

constexpr double kSphereVolume = 4.0 / 3.0 * kPi;  // of the unit sphere

// A UV sphere: `rings` bands of latitude, `segments` of longitude; each pole a fan of
// `segments` triangles (valence `segments`), slivers next to the poles.
TriMesh uvSphere(double radius, int rings, int segments) {
  TriMesh m;
  m.positions.push_back({0, radius, 0});
  for (int i = 1; i < rings; ++i) {
    const double theta = kPi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * kPi * j / segments;
      m.positions.push_back({radius * std::sin(theta) * std::cos(phi), radius * std::cos(theta),
                             radius * std::sin(theta) * std::sin(phi)});
    }
  }
  m.positions.push_back({0, -radius, 0});
  auto at = [segments](int ring, int j) { return static_cast<uint32_t>(1 + (ring - 1) * segments + j % segments); };
  const auto south = static_cast<uint32_t>(m.positions.size() - 1);
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, at(1, j + 1), at(1, j)});
  for (int i = 1; i < rings - 1; ++i) {
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
    }
  }
  for (int j = 0; j < segments; ++j) m.triangles.push_back({south, at(rings - 1, j), at(rings - 1, j + 1)});
  return m;
}

// The unit icosphere (level 4, 5120 triangles) with a round hole of the given radius cut around +x.
TriMesh sphereWithHole(double holeRadius) {
  const TriMesh sphere = makeIcosphere(1.0, 4);
  const double cut = std::sqrt(1.0 - holeRadius * holeRadius);
  TriMesh m{sphere.positions, {}};
  for (const Triangle& t : sphere.triangles) {
    const Vec3 c = (sphere.positions[t[0]] + sphere.positions[t[1]] + sphere.positions[t[2]]) / 3.0;
    if (c.x < cut) m.triangles.push_back(t);
  }
  return weldVertices(m, 0.0);  // drops the hole's unused vertices
}

// `b` moved by `shift` appended to `a`: separate pieces (overlapping or not).
TriMesh joined(const TriMesh& a, const TriMesh& b, const Vec3& shift) {
  TriMesh m = a;
  const auto base = static_cast<uint32_t>(a.positions.size());
  for (const Vec3& p : b.positions) m.positions.push_back(p + shift);
  for (const Triangle& t : b.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return m;
}

// An icosphere with an extra triangle on the edge of its triangle 0 (a non-manifold fin), its
// third corner at `reach` times the unit radius along that triangle's centre: inside the body
// (an internal face, reach < 1) or sticking out (reach > 1).
TriMesh sphereWithFin(double reach) {
  TriMesh m = makeIcosphere(1.0, 3);
  const Triangle t = m.triangles[0];
  m.positions.push_back(normalized(m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) * reach);
  m.triangles.push_back({t[0], t[1], static_cast<uint32_t>(m.positions.size() - 1)});
  return m;
}

// Volume of the union of two unit spheres whose centres are d apart (d < 2).
double twoSpheresVolume(double d) {
  const double lens = kPi * (4.0 + d) * (2.0 - d) * (2.0 - d) / 12.0;
  return 2.0 * kSphereVolume - lens;
}

double minAngleDegrees(const TriMesh& m) {
  double minAngle = 180.0;
  for (const Triangle& t : m.triangles) {
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec3 a = m.positions[t[(k + 1) % 3]] - m.positions[t[k]];
      const Vec3 b = m.positions[t[(k + 2) % 3]] - m.positions[t[k]];
      minAngle = std::min(minAngle, std::atan2(length(cross(a, b)), dot(a, b)) * 180.0 / kPi);
    }
  }
  return minAngle;
}

double meanEdge(const TriMesh& m) {
  double sum = 0.0;
  for (const Triangle& t : m.triangles) {
    for (std::size_t k = 0; k < 3; ++k) sum += length(m.positions[t[(k + 1) % 3]] - m.positions[t[k]]);
  }
  return sum / static_cast<double>(3 * m.triangles.size());
}

ProxyOptions edgeOptions(double edge) {
  ProxyOptions options;
  options.targetEdge = edge;
  return options;
}

// Builds the proxy and checks what every proxy must be: one closed, outward, manifold piece
// (findManifoldProblem), not self-intersecting, min angle above `minAngle`, mean edge within 10%
// of the edge used, volume within `volumeTolerance` of `referenceVolume`; and, unless `minAngle`
// allows thinner triangles than needsProxy does, no reason for a proxy of its own (valence at
// most 12, no angle below 10 degrees, edges within 10x). Prints the numbers.
ProxyResult checkedProxy(const char* name, const TriMesh& input, const ProxyOptions& options, double referenceVolume,
                         double volumeTolerance = 0.03, double minAngle = 25.0) {
  ProxyResult result = buildProxy(input, options);
  const TriMesh& m = result.mesh;
  EXPECT_EQ(findManifoldProblem(m), std::nullopt) << name;
  EXPECT_FALSE(result.selfIntersecting) << name;
  if (minAngle >= kProxyMinAngleDegrees) {
    EXPECT_EQ(needsProxy(m, 0), std::nullopt) << name;
  }
  const double volume = signedVolume(m.positions, m.triangles);
  EXPECT_GT(volume, 0.0) << name;
  EXPECT_NEAR(volume / referenceVolume, 1.0, volumeTolerance) << name;
  const double angle = minAngleDegrees(m);
  EXPECT_GT(angle, minAngle) << name;
  const double edge = meanEdge(m);
  EXPECT_NEAR(edge / result.edge, 1.0, 0.1) << name;
  std::printf("[ proxy    ] %-14s %zu -> %zu vertices, min angle %.1f deg, mean edge %.3f x target, "
              "volume %.4f x reference, offset %.3g\n             %s\n",
              name, input.positions.size(), m.positions.size(), angle, edge / result.edge,
              volume / referenceVolume, result.offset, result.summary.c_str());
  return result;
}

using test::errorOf;

bool contains(const std::optional<std::string>& text, const std::string& part) {
  return text && text->find(part) != std::string::npos;
}

TEST(Proxy, ClosedIcosphere) {
  const TriMesh ico = makeIcosphere(1.0, 3);
  checkedProxy("icosphere", ico, edgeOptions(0.1), signedVolume(ico.positions, ico.triangles));
}

TEST(Proxy, UvSphereWithPoleFans) {
  const TriMesh uv = uvSphere(1.0, 24, 48);
  ASSERT_EQ(findManifoldProblem(uv), std::nullopt);
  checkedProxy("uv sphere", uv, edgeOptions(0.1), signedVolume(uv.positions, uv.triangles));
}

TEST(Proxy, SphereWithHoleIsClosedOver) {
  // A hole of radius 0.15 is narrower than alpha (2.5 x 0.1): the wrap passes over it.
  const ProxyResult r = checkedProxy("hole", sphereWithHole(0.15), edgeOptions(0.1), kSphereVolume);
  EXPECT_NE(r.summary.find("(open)"), std::string::npos) << r.summary;
}

TEST(Proxy, OverlappingSpheresBecomeOne) {
  const ProxyResult r = checkedProxy("two overlapping", joined(makeIcosphere(1.0, 3), makeIcosphere(1.0, 3), {1, 0, 0}),
                                     edgeOptions(0.1), twoSpheresVolume(1.0));
  EXPECT_NE(r.summary.find("2 pieces"), std::string::npos) << r.summary;
  EXPECT_EQ(r.droppedPieces, 0u);
}

TEST(Proxy, SeparateSpheresKeepTheLargest) {
  const ProxyResult r = checkedProxy("two apart", joined(makeIcosphere(1.0, 3), makeIcosphere(0.5, 3), {4, 0, 0}),
                                     edgeOptions(0.1), kSphereVolume);
  EXPECT_EQ(r.droppedPieces, 1u);
  EXPECT_NE(r.summary.find("kept the largest of 2"), std::string::npos) << r.summary;
  for (const Vec3& p : r.mesh.positions) EXPECT_LT(p.x, 1.5);  // the unit sphere, not the small one
}

TEST(Proxy, FlippedFace) {
  TriMesh m = makeIcosphere(1.0, 3);
  const double volume = signedVolume(m.positions, m.triangles);
  std::swap(m.triangles[5][1], m.triangles[5][2]);
  const ProxyResult r = checkedProxy("flipped face", m, edgeOptions(0.1), volume);
  EXPECT_NE(r.summary.find("inconsistently oriented"), std::string::npos) << r.summary;
}

TEST(Proxy, InsideOutMeshGivesAnOutwardProxy) {
  TriMesh m = makeIcosphere(1.0, 3);
  const double volume = signedVolume(m.positions, m.triangles);
  for (Triangle& t : m.triangles) std::swap(t[1], t[2]);
  const ProxyResult r = checkedProxy("inside out", m, edgeOptions(0.1), volume);
  EXPECT_NE(r.summary.find("(inside out)"), std::string::npos) << r.summary;
}

TEST(Proxy, NonManifoldFinInside) {
  // An internal face on an edge of the surface: the wrap sees only the outside.
  const TriMesh m = sphereWithFin(0.3);
  ASSERT_TRUE(contains(findManifoldProblem(m), "non-manifold edge"));
  const TriMesh ico = makeIcosphere(1.0, 3);
  checkedProxy("fin inside", m, edgeOptions(0.1), signedVolume(ico.positions, ico.triangles));
}

TEST(Proxy, NonManifoldFinOutside) {
  // A fin sticking out 1 radius, far thinner than the edge: it is wrapped as a thin blade, so
  // its proxy has thinner triangles (about 10 degrees at the blade's tip) and needs the doubled
  // offset not to fold through itself.
  const TriMesh ico = makeIcosphere(1.0, 3);
  const ProxyResult r = checkedProxy("fin outside", sphereWithFin(2.0), edgeOptions(0.1),
                                     signedVolume(ico.positions, ico.triangles), 0.03, 10.0);
  EXPECT_GT(r.offset, 0.05 * 0.1);
}

TEST(Proxy, SelfIntersectingInput) {
  // The north pole pushed through the south side: a closed manifold that crosses itself.
  TriMesh m = makeIcosphere(1.0, 2);
  const auto top = static_cast<std::size_t>(
      std::max_element(m.positions.begin(), m.positions.end(), [](const Vec3& a, const Vec3& b) { return a.y < b.y; }) -
      m.positions.begin());
  m.positions[top] = {0.0, -1.5, 0.0};
  ASSERT_EQ(findManifoldProblem(m), std::nullopt);
  EXPECT_TRUE(contains(needsProxy(m, 0), "self-intersecting")) << needsProxy(m, 0).value_or("nothing");
  const ProxyResult r = buildProxy(m, edgeOptions(0.1));
  EXPECT_EQ(findManifoldProblem(r.mesh), std::nullopt);
  EXPECT_EQ(needsProxy(r.mesh, 0), std::nullopt);
  EXPECT_GT(signedVolume(r.mesh.positions, r.mesh.triangles), 0.0);
}

TEST(Proxy, OpenSheetBecomesAThinSlab) {
  const TriMesh sheet{{{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{{0, 1, 2}, {0, 2, 3}}}};
  const ProxyResult r = buildProxy(sheet, edgeOptions(0.1));
  EXPECT_EQ(findManifoldProblem(r.mesh), std::nullopt);
  EXPECT_FALSE(r.selfIntersecting);
  EXPECT_GT(signedVolume(r.mesh.positions, r.mesh.triangles), 0.0);
  const Bounds b = boundsOf(r.mesh.positions);
  EXPECT_LT(b.size().y, 2.5 * r.offset);  // as thin as the wrap's two offsets
  EXPECT_GT(b.size().x, 1.0);
}

TEST(Proxy, VeryFineSphereToATargetVertexCount) {
  // 100352 triangles (50178 vertices) down to about 500 vertices, 100x fewer.
  const TriMesh fine = makeOctahedronSphere(1.0, 112);
  ProxyOptions options;
  options.targetVertices = 500;
  const ProxyResult r = checkedProxy("very fine", fine, options, signedVolume(fine.positions, fine.triangles));
  EXPECT_NEAR(static_cast<double>(r.mesh.positions.size()) / 500.0, 1.0, 0.15);
}

TEST(Proxy, Deterministic) {
  const TriMesh input = joined(makeIcosphere(1.0, 3), sphereWithFin(2.0), {1, 0, 0});
  const ProxyResult a = buildProxy(input, edgeOptions(0.1));
  const ProxyResult b = buildProxy(input, edgeOptions(0.1));
  ASSERT_EQ(a.mesh.positions.size(), b.mesh.positions.size());
  EXPECT_TRUE(a.mesh.positions == b.mesh.positions);  // bit for bit
  EXPECT_TRUE(a.mesh.triangles == b.mesh.triangles);
  EXPECT_EQ(a.summary, b.summary);
}

TEST(Proxy, UnusableInputThrows) {
  EXPECT_NE(errorOf([] { buildProxy(TriMesh{}, edgeOptions(0.1)); }).find("no triangle with area"), std::string::npos);
  const TriMesh line{{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{{0, 1, 2}}}};
  EXPECT_NE(errorOf([&] { buildProxy(line, edgeOptions(0.1)); }).find("no triangle with area"), std::string::npos);
  const TriMesh outOfRange{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{{0, 1, 3}}}};
  EXPECT_NE(errorOf([&] { buildProxy(outOfRange, edgeOptions(0.1)); }).find("refers to vertex 3"), std::string::npos);
  TriMesh nan = makeIcosphere(1.0, 1);
  nan.positions[4].y = std::nan("");
  EXPECT_NE(errorOf([&] { buildProxy(nan, edgeOptions(0.1)); }).find("vertex 4 has a non-finite"), std::string::npos);
  EXPECT_NE(errorOf([] { buildProxy(makeIcosphere(1.0, 1), ProxyOptions{}); }).find("target"), std::string::npos);
  EXPECT_NE(errorOf([] { buildProxy(makeIcosphere(1.0, 1), edgeOptions(1e-5)); }).find("too many"), std::string::npos);
  EXPECT_NE(errorOf([] { buildProxy(makeIcosphere(1.0, 1), edgeOptions(-1.0)); }).find("finite positive"),
            std::string::npos);
}

TEST(NeedsProxy, GoodMeshesNeedNone) {
  for (int level = 0; level <= 4; ++level) EXPECT_EQ(needsProxy(makeIcosphere(1.0, level), 0), std::nullopt) << level;
  EXPECT_EQ(needsProxy(makeOctahedronSphere(1.0, 6), 0), std::nullopt);
  EXPECT_EQ(needsProxy(makeIcosphere(1.0, 3), 642), std::nullopt);  // exactly at the limit
}

TEST(NeedsProxy, BadMeshesSayWhy) {
  EXPECT_TRUE(contains(needsProxy(sphereWithHole(0.15), 0), "hole"));
  EXPECT_TRUE(contains(needsProxy(sphereWithFin(0.3), 0), "non-manifold edge"));
  EXPECT_TRUE(contains(needsProxy(joined(makeIcosphere(1, 2), makeIcosphere(1, 2), {1, 0, 0}), 0), "separate pieces"));
  TriMesh flipped = makeIcosphere(1.0, 2);
  std::swap(flipped.triangles[5][1], flipped.triangles[5][2]);
  EXPECT_TRUE(contains(needsProxy(flipped, 0), "flipped face"));
  EXPECT_TRUE(contains(needsProxy(makeIcosphere(1.0, 3), 641), "642 vertices, more than 641"));
  EXPECT_TRUE(contains(needsProxy(uvSphere(1.0, 24, 48), 0), "max valence 48"));

  // Slivers: one vertex moved 95% of the way to a neighbour.
  TriMesh sliver = makeIcosphere(1.0, 3);
  const Triangle& t = sliver.triangles[0];
  sliver.positions[t[0]] = sliver.positions[t[0]] + (sliver.positions[t[1]] - sliver.positions[t[0]]) * 0.95;
  ASSERT_EQ(findManifoldProblem(sliver), std::nullopt);
  EXPECT_TRUE(contains(needsProxy(sliver, 0), "min angle")) << needsProxy(sliver, 0).value_or("nothing");

  // Uneven edges, well-shaped triangles: the icosphere's radius grown smoothly 12x from bottom to top.
  TriMesh graded = makeIcosphere(1.0, 3);
  for (Vec3& p : graded.positions) p = p * std::exp(1.25 * p.y);
  ASSERT_EQ(findManifoldProblem(graded), std::nullopt);
  EXPECT_TRUE(contains(needsProxy(graded, 0), "edge lengths differ by")) << needsProxy(graded, 0).value_or("nothing");
}

}  // namespace
}  // namespace springy

// The geometry of body-body and self contact (sim/contact_geometry.h, sim/contact_bvh.h):
// closest points against an independent long-double reference, continuous vertex-triangle and
// edge-edge tests against analytic times and against brute-force sampling of the distance over
// the step, and the BVH's pair queries against the O(N^2) pair set.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "random.h"
#include "sim/contact_bvh.h"
#include "sim/contact_geometry.h"

namespace springy {
namespace {

using test::Random;

// ---------------------------------------------------------------------------------------------
// Reference distances in long double, computed differently from the code under test: the
// minimum over the features (the interior solution of the normal equations when it lies inside,
// and every point-segment distance), which is the distance to the convex primitive.

using Real = long double;
struct RVec {
  Real x, y, z;
};
RVec toReal(const Vec3& v) { return {v.x, v.y, v.z}; }
RVec operator-(const RVec& a, const RVec& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
RVec operator+(const RVec& a, const RVec& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
RVec operator*(const RVec& a, Real s) { return {a.x * s, a.y * s, a.z * s}; }
Real dotR(const RVec& a, const RVec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
RVec lerpR(const Vec3& a, const Vec3& b, Real s) { return toReal(a) + (toReal(b) - toReal(a)) * s; }

Real pointSegment2(const RVec& p, const RVec& a, const RVec& b) {
  const RVec e = b - a;
  const Real ee = dotR(e, e);
  Real t = ee > 0 ? dotR(p - a, e) / ee : 0;
  t = std::clamp(t, Real(0), Real(1));
  const RVec d = a + e * t - p;
  return dotR(d, d);
}

Real refPointTriangle(const RVec& p, const RVec& a, const RVec& b, const RVec& c) {
  Real best = std::min({pointSegment2(p, a, b), pointSegment2(p, b, c), pointSegment2(p, c, a)});
  const RVec e1 = b - a, e2 = c - a, w = p - a;
  const Real g11 = dotR(e1, e1), g12 = dotR(e1, e2), g22 = dotR(e2, e2);
  const Real det = g11 * g22 - g12 * g12;
  if (det > Real(1e-30) * g11 * g22) {
    const Real u = (g22 * dotR(w, e1) - g12 * dotR(w, e2)) / det;
    const Real v = (g11 * dotR(w, e2) - g12 * dotR(w, e1)) / det;
    if (u >= 0 && v >= 0 && u + v <= 1) {
      const RVec d = a + e1 * u + e2 * v - p;
      best = std::min(best, dotR(d, d));
    }
  }
  return std::sqrt(best);
}

Real refSegmentSegment(const RVec& p0, const RVec& p1, const RVec& q0, const RVec& q1) {
  Real best = std::min(
      {pointSegment2(p0, q0, q1), pointSegment2(p1, q0, q1), pointSegment2(q0, p0, p1), pointSegment2(q1, p0, p1)});
  const RVec d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const Real a = dotR(d1, d1), e = dotR(d2, d2), b = dotR(d1, d2), c = dotR(d1, r), f = dotR(d2, r);
  const Real det = a * e - b * b;
  if (det > Real(1e-30) * a * e) {
    const Real s = (b * f - c * e) / det, t = (a * f - b * c) / det;
    if (s >= 0 && s <= 1 && t >= 0 && t <= 1) {
      const RVec d = r + d1 * s - d2 * t;
      best = std::min(best, dotR(d, d));
    }
  }
  return std::sqrt(best);
}

// Distances of moving pairs at fraction s.
double vtDistance(const Motion m[4], double s) {
  return static_cast<double>(refPointTriangle(lerpR(m[0].start, m[0].end, s), lerpR(m[1].start, m[1].end, s),
                                              lerpR(m[2].start, m[2].end, s), lerpR(m[3].start, m[3].end, s)));
}
double eeDistance(const Motion m[4], double s) {
  return static_cast<double>(refSegmentSegment(lerpR(m[0].start, m[0].end, s), lerpR(m[1].start, m[1].end, s),
                                               lerpR(m[2].start, m[2].end, s), lerpR(m[3].start, m[3].end, s)));
}

double maxAbs(const Vec3& v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

// The scale contactTolerance is given: the largest coordinate of any corner of the difference
// set (first primitive's point minus second's), at the start or the end.
double pairScale(const Motion m[4], bool edges) {
  double scale = 0.0;
  const int firstCount = edges ? 2 : 1;
  for (int i = 0; i < firstCount; ++i) {
    for (int j = firstCount; j < 4; ++j) {
      scale = std::max({scale, maxAbs(m[i].start - m[j].start), maxAbs(m[i].end - m[j].end)});
    }
  }
  return scale;
}
// Largest relative speed of two corners (per unit s): the Lipschitz constant of the distance.
double pairSpeed(const Motion m[4], bool edges) {
  double speed = 0.0;
  const int firstCount = edges ? 2 : 1;
  for (int i = 0; i < firstCount; ++i) {
    for (int j = firstCount; j < 4; ++j) {
      speed = std::max(speed, length((m[i].end - m[i].start) - (m[j].end - m[j].start)));
    }
  }
  return speed;
}

std::string describe(const Motion m[4], double h) {
  char buffer[1024];
  std::string out = "thickness " + std::to_string(h) + ":";
  for (int i = 0; i < 4; ++i) {
    std::snprintf(buffer, sizeof buffer, " {(%.17g, %.17g, %.17g) -> (%.17g, %.17g, %.17g)}", m[i].start.x,
                  m[i].start.y, m[i].start.z, m[i].end.x, m[i].end.y, m[i].end.z);
    out += buffer;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Closest points.

TEST(ClosestPoints, PointTriangleEveryRegion) {
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  struct Case {
    Vec3 p;
    double w[3];
    double d2;
  };
  const Case cases[] = {
      {{-1, -1, 1}, {1, 0, 0}, 3.0},               // corner a
      {{2, -0.5, 0}, {0, 1, 0}, 1.25},             // corner b
      {{-0.5, 2, 0}, {0, 0, 1}, 1.25},             // corner c
      {{0.5, -1, 2}, {0.5, 0.5, 0}, 5.0},          // edge ab
      {{-1, 0.25, 0}, {0.75, 0, 0.25}, 1.0},       // edge ac
      {{1, 1, 0}, {0, 0.5, 0.5}, 0.5},             // edge bc
      {{0.25, 0.25, -3}, {0.5, 0.25, 0.25}, 9.0},  // face, below
  };
  for (const Case& k : cases) {
    const PointTriangleClosest q = closestPointTriangle(k.p, a, b, c);
    EXPECT_NEAR(q.distanceSquared, k.d2, 1e-15);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(q.weight[i], k.w[i], 1e-15) << "weight " << i;
  }
}

TEST(ClosestPoints, DegenerateTriangles) {
  // Collinear corners, c beyond b: the closest point is on the segment a c.
  PointTriangleClosest q = closestPointTriangle({1.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  Vec3 x = Vec3{0, 0, 0} * q.weight[0] + Vec3{1, 0, 0} * q.weight[1] + Vec3{2, 0, 0} * q.weight[2];
  EXPECT_NEAR(x.x, 1.5, 1e-15);
  // All corners in one point.
  q = closestPointTriangle({1, 2, 4}, {1, 2, 3}, {1, 2, 3}, {1, 2, 3});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  EXPECT_NEAR(q.weight[0] + q.weight[1] + q.weight[2], 1.0, 1e-15);
  // Two corners in one point, the point beside.
  q = closestPointTriangle({0.5, -1, 0}, {0, 0, 0}, {1, 0, 0}, {1, 0, 0});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  // The point exactly on a degenerate triangle, and on every kind of corner.
  for (const Vec3& p : {Vec3{0.7, 0, 0}, Vec3{0, 0, 0}, Vec3{2, 0, 0}}) {
    q = closestPointTriangle(p, {0, 0, 0}, {2, 0, 0}, {1, 0, 0});
    EXPECT_EQ(q.distanceSquared, 0.0);
  }
}

TEST(ClosestPoints, SegmentSegmentCases) {
  // Crossing like an X, one above the other.
  SegmentSegmentClosest q = closestSegmentSegment({-1, 0, 1}, {1, 0, 1}, {0, -1, 0}, {0, 1, 0});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  EXPECT_NEAR(q.s, 0.5, 1e-15);
  EXPECT_NEAR(q.t, 0.5, 1e-15);
  // Parallel and overlapping: any pair in the overlap, at distance 1.
  q = closestSegmentSegment({0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {3, 1, 0});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  EXPECT_NEAR(2 * q.s, 1 + 2 * q.t, 1e-15);  // the two points one above the other
  EXPECT_GE(q.s, 0.5);
  // Collinear, apart: end to end.
  q = closestSegmentSegment({0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  EXPECT_EQ(q.s, 1.0);
  EXPECT_EQ(q.t, 0.0);
  // T: an end of one against the inside of the other.
  q = closestSegmentSegment({0, 0, 0}, {0, 0, 1}, {-1, 0, 2}, {1, 0, 2});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  EXPECT_EQ(q.s, 1.0);
  EXPECT_NEAR(q.t, 0.5, 1e-15);
  // Zero-length first, second, both.
  q = closestSegmentSegment({0.5, 1, 0}, {0.5, 1, 0}, {0, 0, 0}, {1, 0, 0});
  EXPECT_NEAR(q.distanceSquared, 1.0, 1e-15);
  EXPECT_NEAR(q.t, 0.5, 1e-15);
  q = closestSegmentSegment({0, 0, 0}, {1, 0, 0}, {0.25, 0, 2}, {0.25, 0, 2});
  EXPECT_NEAR(q.distanceSquared, 4.0, 1e-15);
  EXPECT_NEAR(q.s, 0.25, 1e-15);
  q = closestSegmentSegment({0, 0, 0}, {0, 0, 0}, {0, 3, 4}, {0, 3, 4});
  EXPECT_NEAR(q.distanceSquared, 25.0, 1e-13);
}

// Random triangles and segments, well-shaped and degenerate (collinear, coincident corners,
// slivers, parallel and nearly parallel segments, zero length): the distance agrees with the
// reference to 1e-13 of the scale, the weights are valid and reproduce the distance.
TEST(ClosestPoints, RandomAgainstReference) {
  Random random(20240616);
  int failures = 0;
  for (int n = 0; n < 20000; ++n) {
    const int kind = static_cast<int>(random.below(6));
    Vec3 a = random.point(-1, 1), b = random.point(-1, 1), c = random.point(-1, 1);
    const Vec3 p = random.point(-1.5, 1.5);
    const double tiny = std::pow(10.0, -random.uniform(3, 15));
    if (kind == 1) c = a + (b - a) * random.uniform(-1, 2);                             // collinear
    if (kind == 2) b = a;                                                               // two corners coincide
    if (kind == 3) c = a + (b - a) * random.uniform(0, 1) + random.point(-tiny, tiny);  // sliver
    if (kind == 4) a = b = c;                                                           // one point
    const PointTriangleClosest q = closestPointTriangle(p, a, b, c);
    const double ref = static_cast<double>(refPointTriangle(toReal(p), toReal(a), toReal(b), toReal(c)));
    const double sum = q.weight[0] + q.weight[1] + q.weight[2];
    const Vec3 x = a * q.weight[0] + b * q.weight[1] + c * q.weight[2];
    const bool ok = std::fabs(std::sqrt(q.distanceSquared) - ref) <= 1e-13 && std::fabs(length(x - p) - ref) <= 1e-13 &&
                    std::fabs(sum - 1.0) <= 1e-14 && std::min({q.weight[0], q.weight[1], q.weight[2]}) >= 0.0 &&
                    std::max({q.weight[0], q.weight[1], q.weight[2]}) <= 1.0;
    if (!ok && ++failures <= 5) {
      ADD_FAILURE() << "triangle kind " << kind << " case " << n << ": distance " << std::sqrt(q.distanceSquared)
                    << " reference " << ref;
    }

    Vec3 p0 = random.point(-1, 1), p1 = random.point(-1, 1), q0 = random.point(-1, 1), q1 = random.point(-1, 1);
    if (kind == 1) q1 = q0 + (p1 - p0) * random.uniform(-2, 2);                              // parallel
    if (kind == 2) q1 = q0 + (p1 - p0) * random.uniform(-2, 2) + random.point(-tiny, tiny);  // nearly
    if (kind == 3) p1 = p0;                                                                  // zero length
    if (kind == 4) p1 = p0, q1 = q0;
    if (kind == 5) q0 = p0 + (p1 - p0) * 3.0, q1 = p0 + (p1 - p0) * random.uniform(-1, 2);  // collinear
    const SegmentSegmentClosest r = closestSegmentSegment(p0, p1, q0, q1);
    const double refSeg = static_cast<double>(refSegmentSegment(toReal(p0), toReal(p1), toReal(q0), toReal(q1)));
    const Vec3 d = (p0 + (p1 - p0) * r.s) - (q0 + (q1 - q0) * r.t);
    const bool segOk = std::fabs(std::sqrt(r.distanceSquared) - refSeg) <= 1e-13 &&
                       std::fabs(length(d) - refSeg) <= 1e-13 && r.s >= 0.0 && r.s <= 1.0 && r.t >= 0.0 && r.t <= 1.0;
    if (!segOk && ++failures <= 5) {
      ADD_FAILURE() << "segment kind " << kind << " case " << n << ": distance " << std::sqrt(r.distanceSquared)
                    << " reference " << refSeg;
    }
  }
  EXPECT_EQ(failures, 0);
}

// ---------------------------------------------------------------------------------------------
// Continuous tests: analytic cases.

Motion still(const Vec3& p) { return {p, p}; }
Motion moving(const Vec3& p, const Vec3& travel) { return {p, p + travel}; }

TEST(VertexTriangleImpact, StraightDownAtTheExactFraction) {
  const Motion a = still({-1, -1, 0}), b = still({2, -1, 0}), c = still({-1, 2, 0});
  // Gap 1, travel 2: contact at s = (gap - thickness) / travel, reached from above within the
  // tolerance (never after it).
  for (const double h : {0.0, 0.1, 0.5}) {
    VertexTriangleContact contact;
    ASSERT_TRUE(vertexTriangleImpact(moving({0.2, 0.3, 1}, {0, 0, -2}), a, b, c, h, contact)) << h;
    const double exact = (1.0 - h) / 2.0;
    EXPECT_LE(contact.fraction, exact);
    EXPECT_GE(contact.fraction, exact - 1e-7);
    EXPECT_NEAR(contact.distance, h, 1e-7);
    EXPECT_NEAR(contact.weight[0], 1.0 - 0.4 - 1.3 / 3.0, 1e-12);
    EXPECT_NEAR(contact.weight[1], 0.4, 1e-12);
    EXPECT_NEAR(contact.weight[2], 1.3 / 3.0, 1e-12);
    EXPECT_NEAR(contact.normal.z, 1.0, 1e-12);  // the side it came from
    EXPECT_LE(contact.steps, 3);
  }
  // From below: the normal points down.
  VertexTriangleContact contact;
  ASSERT_TRUE(vertexTriangleImpact(moving({0.2, 0.3, -1}, {0, 0, 2}), a, b, c, 0.0, contact));
  EXPECT_NEAR(contact.fraction, 0.5, 1e-8);
  EXPECT_NEAR(contact.normal.z, -1.0, 1e-12);
  // Both moving: the triangle up by 1, the point down by 1 (relative travel 2).
  const Vec3 up{0, 0, 1};
  ASSERT_TRUE(vertexTriangleImpact(moving({0.2, 0.3, 1}, {0, 0, -1}), moving({-1, -1, 0}, up), moving({2, -1, 0}, up),
                                   moving({-1, 2, 0}, up), 0.1, contact));
  EXPECT_NEAR(contact.fraction, 0.45, 1e-8);
  EXPECT_LE(contact.fraction, 0.45);
  // Very fast: through the triangle in one step, both end points far away.
  ASSERT_TRUE(vertexTriangleImpact(moving({0.2, 0.3, 100}, {0, 0, -200}), a, b, c, 0.0, contact));
  EXPECT_NEAR(contact.fraction, 0.5, 1e-9);
  EXPECT_NEAR(contact.normal.z, 1.0, 1e-12);
}

TEST(VertexTriangleImpact, PassingBesideTheTriangle) {
  const Motion a = still({0, 0, 0}), b = still({1, 0, 0}), c = still({0, 1, 0});
  // The path passes 0.5 from the edge ab at its closest (s = 0.5).
  const Motion x = moving({0.25, -0.5, 1}, {0, 0, -2});
  VertexTriangleContact contact;
  EXPECT_FALSE(vertexTriangleImpact(x, a, b, c, 0.0, contact));
  EXPECT_FALSE(vertexTriangleImpact(x, a, b, c, 0.4, contact));
  EXPECT_FALSE(vertexTriangleImpact(x, a, b, c, 0.5 * (1 - 1e-6), contact));
  // Thickness 0.6: distance^2 = 0.25 + z^2 = 0.36 at z = sqrt(0.11).
  ASSERT_TRUE(vertexTriangleImpact(x, a, b, c, 0.6, contact));
  const double exact = (1.0 - std::sqrt(0.11)) / 2.0;
  EXPECT_LE(contact.fraction, exact);
  EXPECT_GE(contact.fraction, exact - 1e-7);
  EXPECT_NEAR(contact.weight[0], 0.75, 1e-7);
  EXPECT_NEAR(contact.weight[1], 0.25, 1e-7);
  EXPECT_EQ(contact.weight[2], 0.0);
  EXPECT_NEAR(contact.normal.x, 0.0, 1e-7);
  EXPECT_NEAR(contact.normal.y, -0.5 / 0.6, 1e-7);
  EXPECT_NEAR(contact.normal.z, std::sqrt(0.11) / 0.6, 1e-7);
}

TEST(VertexTriangleImpact, StartingWithinThicknessReportsZero) {
  const Motion a = still({0, 0, 0}), b = still({1, 0, 0}), c = still({0, 1, 0});
  VertexTriangleContact contact;
  // Moving away, but within thickness at the start.
  ASSERT_TRUE(vertexTriangleImpact(moving({0.2, 0.2, 0.05}, {0, 0, 1}), a, b, c, 0.1, contact));
  EXPECT_EQ(contact.fraction, 0.0);
  EXPECT_NEAR(contact.distance, 0.05, 1e-15);
  EXPECT_NEAR(contact.normal.z, 1.0, 1e-15);
  // Exactly on the triangle, not moving: a unit normal all the same.
  ASSERT_TRUE(vertexTriangleImpact(still({0.2, 0.2, 0}), a, b, c, 0.0, contact));
  EXPECT_EQ(contact.fraction, 0.0);
  EXPECT_NEAR(length(contact.normal), 1.0, 1e-15);
}

// Most pairs that the boxes let through stay clear along one direction all step (advance's
// separatedOverStep): those need no closest-point query at all. A pair that comes within the
// thickness is never cleared so: the answers at the threshold are the queries'.
TEST(ContinuousCost, ClearPairsNeedNoQuery) {
  const Motion a = still({0, 0, 0}), b = still({1, 0, 0}), c = still({0, 1, 0});
  VertexTriangleContact vt;
  // Over the face, sliding along it at height 0.3 (clear along the face's normal).
  EXPECT_FALSE(vertexTriangleImpact(moving({0.2, 0.2, 0.3}, {0.3, 0, 0}), a, b, c, 0.2, vt));
  EXPECT_EQ(vt.steps, 0);
  // Beside the face, in its plane, moving along its edge (clear along the line between them).
  EXPECT_FALSE(vertexTriangleImpact(moving({0.3, -0.5, 0}, {0.2, 0, 0}), a, b, c, 0.2, vt));
  EXPECT_EQ(vt.steps, 0);
  // Approaching to just outside the thickness, then to just inside it.
  EXPECT_FALSE(vertexTriangleImpact(moving({0.2, 0.2, 1}, {0, 0, -0.8 + 1e-6}), a, b, c, 0.2, vt));
  ASSERT_TRUE(vertexTriangleImpact(moving({0.2, 0.2, 1}, {0, 0, -0.8 - 1e-6}), a, b, c, 0.2, vt));
  EXPECT_GT(vt.steps, 0);
  // Two edges one over the other, both moving along x: clear along their common normal.
  EdgeEdgeContact ee;
  const Vec3 along{0.5, 0, 0};
  EXPECT_FALSE(edgeEdgeImpact(moving({0, 0, 0.25}, along), moving({1, 0, 0.25}, along), moving({0.5, -0.5, 0}, along),
                              moving({0.5, 0.5, 0}, along), 0.2, ee));
  EXPECT_EQ(ee.steps, 0);
  ASSERT_TRUE(edgeEdgeImpact(moving({0, 0, 0.25}, along), moving({1, 0, 0.25}, along), moving({0.5, -0.5, 0}, along),
                             moving({0.5, 0.5, 0}, along), 0.3, ee));
  EXPECT_EQ(ee.fraction, 0.0);
}

TEST(EdgeEdgeImpact, CrossingLikeAnXAtAKnownTime) {
  // p runs along x at height 1 - 2s (y = 0.3, x from -1 to 3); q along y at height 0 (x = 0, y
  // from -2 to 2). Above each other at a = 0.25, b = 0.575; they cross at s = 0.5.
  const Motion p0 = moving({-1, 0.3, 1}, {0, 0, -2}), p1 = moving({3, 0.3, 1}, {0, 0, -2});
  const Motion q0 = still({0, -2, 0}), q1 = still({0, 2, 0});
  for (const double h : {0.0, 0.1, 0.4}) {
    EdgeEdgeContact contact;
    ASSERT_TRUE(edgeEdgeImpact(p0, p1, q0, q1, h, contact)) << h;
    const double exact = (1.0 - h) / 2.0;
    EXPECT_LE(contact.fraction, exact);
    EXPECT_GE(contact.fraction, exact - 1e-7);
    EXPECT_NEAR(contact.a, 0.25, 1e-12);
    EXPECT_NEAR(contact.b, 0.575, 1e-12);
    EXPECT_NEAR(contact.normal.z, 1.0, 1e-12);  // from q toward p
    EXPECT_NEAR(contact.distance, h, 1e-7);
  }
  // Swapped roles: the normal points from p (now second) toward q, down.
  EdgeEdgeContact contact;
  ASSERT_TRUE(edgeEdgeImpact(q0, q1, p0, p1, 0.0, contact));
  EXPECT_NEAR(contact.fraction, 0.5, 1e-8);
  EXPECT_NEAR(contact.normal.z, -1.0, 1e-12);
  EXPECT_NEAR(contact.a, 0.575, 1e-12);
  EXPECT_NEAR(contact.b, 0.25, 1e-12);
  // q turning about its middle (ends moving down and up), p coming down onto it: the lines are
  // (1 - s) / sqrt(1 + s^2 / 4) apart, so with thickness 0 they touch exactly at the end, s = 1.
  const Motion r0 = moving({0, -2, 0}, {0, 0, -1}), r1 = moving({0, 2, 0}, {0, 0, 1});
  const Motion d0 = moving({-1, 0, 1}, {0, 0, -1}), d1 = moving({3, 0, 1}, {0, 0, -1});
  ASSERT_TRUE(edgeEdgeImpact(d0, d1, r0, r1, 0.0, contact));
  EXPECT_LE(contact.fraction, 1.0);
  EXPECT_GE(contact.fraction, 1.0 - 1e-8);
  // Thickness 0.2: the root of 1 - s = 0.2 sqrt(1 + s^2 / 4), by bisection.
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (1.0 - mid > 0.2 * std::sqrt(1.0 + mid * mid / 4.0) ? lo : hi) = mid;
  }
  ASSERT_TRUE(edgeEdgeImpact(d0, d1, r0, r1, 0.2, contact));
  EXPECT_LE(contact.fraction, lo + 1e-15);
  EXPECT_GE(contact.fraction, lo - 1e-7);
  // q's closest point is y = s (1 - s) / (2 + s^2 / 2) along it (minimizing y^2 + (1 - s - s y / 2)^2).
  EXPECT_NEAR(contact.a, 0.25, 1e-7);
  EXPECT_NEAR(contact.b, 0.5 + lo * (1 - lo) / (2 + lo * lo / 2) / 4, 1e-7);
}

TEST(EdgeEdgeImpact, ParallelEdges) {
  EdgeEdgeContact contact;
  // One above the other, overlapping in x from 0.5 to 1, approaching: contact at (1 - h) / 2.
  const Motion p0 = moving({0, 0, 1}, {0, 0, -2}), p1 = moving({1, 0, 1}, {0, 0, -2});
  const Motion q0 = still({0.5, 0, 0}), q1 = still({1.5, 0, 0});
  ASSERT_TRUE(edgeEdgeImpact(p0, p1, q0, q1, 0.05, contact));
  EXPECT_LE(contact.fraction, 0.475);
  EXPECT_GE(contact.fraction, 0.475 - 1e-8);
  EXPECT_GE(contact.a, 0.5);
  EXPECT_LE(contact.b, 0.5);
  EXPECT_NEAR(contact.a, 0.5 + contact.b, 1e-12);  // one above the other
  EXPECT_NEAR(contact.normal.z, 1.0, 1e-12);
  EXPECT_NEAR(contact.distance, 0.05, 1e-8);
  // Collinear, sliding end into end, thickness 0: touch when p1 reaches 1.5 at s = 0.25.
  ASSERT_TRUE(edgeEdgeImpact(moving({0, 0, 0}, {2, 0, 0}), moving({1, 0, 0}, {2, 0, 0}), still({1.5, 0, 0}),
                             still({2.5, 0, 0}), 0.0, contact));
  EXPECT_LE(contact.fraction, 0.25);
  EXPECT_GE(contact.fraction, 0.25 - 1e-9);
  EXPECT_EQ(contact.a, 1.0);
  EXPECT_EQ(contact.b, 0.0);
  EXPECT_NEAR(contact.normal.x, -1.0, 1e-6);
  // Side by side 1 apart, sliding along each other: never within 0.9, within 1.5 from the start.
  const Motion s0 = moving({0, 0, 0}, {5, 0, 0}), s1 = moving({1, 0, 0}, {5, 0, 0});
  const Motion t0 = still({0, 1, 0}), t1 = still({1, 1, 0});
  EXPECT_FALSE(edgeEdgeImpact(s0, s1, t0, t1, 0.9, contact));
  EXPECT_LE(contact.steps, 3);
  ASSERT_TRUE(edgeEdgeImpact(s0, s1, t0, t1, 1.5, contact));
  EXPECT_EQ(contact.fraction, 0.0);
}

TEST(Degenerate, ZeroAreaTrianglesAndZeroLengthEdges) {
  VertexTriangleContact vt;
  // Collinear corners along x: a segment. Straight down onto it, gap 1, travel 2.
  const Motion a = still({0, 0, 0}), b = still({2, 0, 0}), c = still({1, 0, 0});
  ASSERT_TRUE(vertexTriangleImpact(moving({1.5, 0, 1}, {0, 0, -2}), a, b, c, 0.1, vt));
  EXPECT_LE(vt.fraction, 0.45);
  EXPECT_GE(vt.fraction, 0.45 - 1e-8);
  EXPECT_NEAR(vt.normal.z, 1.0, 1e-12);
  EXPECT_NEAR(vt.weight[0] + vt.weight[1] + vt.weight[2], 1.0, 1e-15);
  const Vec3 onTriangle = a.start * vt.weight[0] + b.start * vt.weight[1] + c.start * vt.weight[2];
  EXPECT_NEAR(onTriangle.x, 1.5, 1e-12);
  // Passing beside the segment: nothing.
  EXPECT_FALSE(vertexTriangleImpact(moving({1.5, 0.5, 1}, {0, 0, -2}), a, b, c, 0.4, vt));
  // All three corners in one point, thickness 0: the point passes exactly through it.
  const Motion o = still({0, 0, 0});
  ASSERT_TRUE(vertexTriangleImpact(moving({0, 0, 1}, {0, 0, -2}), o, o, o, 0.0, vt));
  EXPECT_NEAR(vt.fraction, 0.5, 1e-9);
  EXPECT_TRUE(isFinite(vt.normal));
  EXPECT_NEAR(length(vt.normal), 1.0, 1e-12);
  // A triangle collapsing to a segment over the step (c moves onto b), under a point that comes
  // down to it while it still covers the point (until s = 5 / 7): contact at (0.3 - 0.05) / 0.6.
  ASSERT_TRUE(vertexTriangleImpact(moving({0.5, 0.2, 0.3}, {0, 0, -0.6}), still({0, 0, 0}), still({1, 0, 0}),
                                   moving({0, 1, 0}, {1, -1, 0}), 0.05, vt));
  EXPECT_LE(vt.fraction, 0.25 / 0.6);
  EXPECT_GE(vt.fraction, 0.25 / 0.6 - 1e-7);
  EXPECT_NEAR(vt.normal.z, 1.0, 1e-12);
  // Coming down later, after it has left the shrinking triangle: 0.17 from its edge at s = 0.95.
  EXPECT_FALSE(vertexTriangleImpact(moving({0.5, 0.2, 1}, {0, 0, -1}), still({0, 0, 0}), still({1, 0, 0}),
                                    moving({0, 1, 0}, {1, -1, 0}), 0.05, vt));
  // Everything in one point, standing still: contact at 0 with a unit normal.
  ASSERT_TRUE(vertexTriangleImpact(o, o, o, o, 0.0, vt));
  EXPECT_EQ(vt.fraction, 0.0);
  EXPECT_NEAR(length(vt.normal), 1.0, 1e-15);

  EdgeEdgeContact ee;
  // A zero-length edge (a point) coming down onto an edge: contact at (1 - h) / 2, b = 0.5.
  const Motion point = moving({0, 0, 1}, {0, 0, -2});
  ASSERT_TRUE(edgeEdgeImpact(point, point, still({-1, 0, 0}), still({1, 0, 0}), 0.1, ee));
  EXPECT_LE(ee.fraction, 0.45);
  EXPECT_GE(ee.fraction, 0.45 - 1e-8);
  EXPECT_NEAR(ee.b, 0.5, 1e-12);
  EXPECT_NEAR(ee.normal.z, 1.0, 1e-12);
  // Both zero length.
  ASSERT_TRUE(edgeEdgeImpact(point, point, o, o, 0.1, ee));
  EXPECT_NEAR(ee.fraction, 0.45, 1e-8);
  ASSERT_TRUE(edgeEdgeImpact(point, point, o, o, 0.0, ee));
  EXPECT_NEAR(ee.fraction, 0.5, 1e-9);
  EXPECT_NEAR(length(ee.normal), 1.0, 1e-12);
  ASSERT_TRUE(edgeEdgeImpact(o, o, o, o, 0.0, ee));
  EXPECT_EQ(ee.fraction, 0.0);
  EXPECT_NEAR(length(ee.normal), 1.0, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Continuous tests against brute force: the distance sampled at 2001 fractions (long double
// reference). What the header guarantees, with tol = contactTolerance(h, scale):
//  (a) if a sample is within h (1 - 1e-6), a contact is reported no later than that sample
//      (so in particular no later than the sample + 1/2000);
//  (b) at the reported fraction the distance is <= h + tol (<= h (1 + 1e-7) + 1e-10 scale), and
//      the reported distance, weights and normal agree with it;
//  (c) every sample before the reported fraction is farther than h + tol / 2 (not too early);
//  (d) no contact is reported when every sample exceeds h + tol + (largest relative corner speed)
//      / 4000: between two samples the distance cannot drop by more than that, so it stays above
//      h + tol everywhere (the 1e-3 margin alone would not make this true: the path can dip
//      between samples).
//  (e) constructed crossings (the two touch at a known s_c) are reported at s <= s_c.

constexpr int kSamples = 2000;
// Random cases per family; define it larger for a longer soak (the counts asserted below scale).
#ifndef SPRINGY_CONTACT_CASES
#define SPRINGY_CONTACT_CASES 800
#endif
constexpr int kCases = SPRINGY_CONTACT_CASES;

struct Stats {
  int cases = 0, contacts = 0, checkedA = 0, checkedD = 0, crossings = 0, stalls = 0, maxSteps = 0;
  long long steps = 0;
  double seconds = 0.0;
  int failures = 0;
};

void fail(Stats& stats, const std::string& what, const Motion m[4], double h) {
  if (++stats.failures <= 5) ADD_FAILURE() << what << "\n  case " << describe(m, h);
}

// One case: m = {x, a, b, c} or {p0, p1, q0, q1}. crossing: the known fraction at which the pair
// touches (distance 0), or < 0.
void check(const Motion m[4], bool edges, double h, double crossing, Stats& stats) {
  ++stats.cases;
  VertexTriangleContact vt;
  EdgeEdgeContact ee;
  const auto start = std::chrono::steady_clock::now();
  const bool found =
      edges ? edgeEdgeImpact(m[0], m[1], m[2], m[3], h, ee) : vertexTriangleImpact(m[0], m[1], m[2], m[3], h, vt);
  stats.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const int steps = edges ? ee.steps : vt.steps;
  stats.steps += steps;
  stats.maxSteps = std::max(stats.maxSteps, steps);
  const double fraction = edges ? ee.fraction : vt.fraction;
  const double scale = pairScale(m, edges), speed = pairSpeed(m, edges);
  // Slack for rounding: of the code under test (about 1e-16 scale) and of the long-double
  // reference's interpolation far from the origin.
  double extent = 0.0;
  for (int i = 0; i < 4; ++i) extent = std::max({extent, maxAbs(m[i].start), maxAbs(m[i].end)});
  const double tol = contactTolerance(h, scale),
               slack = 1e-13 * scale + 8 * static_cast<double>(std::numeric_limits<Real>::epsilon()) * extent;
  const auto distance = [&](double s) { return edges ? eeDistance(m, s) : vtDistance(m, s); };

  double minSample = std::numeric_limits<double>::infinity();
  int firstWithin = -1;
  for (int k = 0; k <= kSamples; ++k) {
    const double s = static_cast<double>(k) / kSamples, d = distance(s);
    minSample = std::min(minSample, d);
    if (firstWithin < 0 && d < h * (1 - 1e-6)) firstWithin = k;
    if (found && s < fraction && d <= h + 0.5 * tol - slack) {  // (c)
      fail(stats,
           "(c) sample at s = " + std::to_string(s) + " before the reported " + std::to_string(fraction) +
               " is within h + tol / 2: " + std::to_string(d),
           m, h);
      break;
    }
  }
  if (firstWithin >= 0) {  // (a)
    ++stats.checkedA;
    const double s = static_cast<double>(firstWithin) / kSamples;
    if (!found || fraction > s + 1e-12) {
      fail(stats,
           "(a) sample at s = " + std::to_string(s) + " is within h but " +
               (found ? "reported later, at " + std::to_string(fraction) : std::string("nothing reported")),
           m, h);
    }
  }
  if (minSample > h + tol + speed / (2 * kSamples) + slack) {  // (d)
    ++stats.checkedD;
    if (found)
      fail(stats, "(d) reported at " + std::to_string(fraction) + " but the pair never comes within h + tol", m, h);
  }
  if (crossing >= 0.0) {  // (e)
    ++stats.crossings;
    if (!found || fraction > crossing + 1e-12) {
      fail(stats,
           "(e) crossing at " + std::to_string(crossing) + " " +
               (found ? "reported later, at " + std::to_string(fraction) : std::string("missed")),
           m, h);
    }
  }
  if (!found) return;
  ++stats.contacts;
  // (b)
  const double d = distance(fraction);
  if (d > h + tol + slack) {
    ++stats.stalls;
    fail(stats,
         "(b) at the reported " + std::to_string(fraction) + " the distance is " + std::to_string(d) +
             ", h + tol = " + std::to_string(h + tol) + ", steps " + std::to_string(steps),
         m, h);
  }
  if (!(fraction >= 0.0 && fraction <= 1.0)) fail(stats, "fraction outside [0, 1]", m, h);
  const Vec3 normal = edges ? ee.normal : vt.normal;
  const double reported = edges ? ee.distance : vt.distance;
  if (std::fabs(reported - d) > 1e-12 * scale) fail(stats, "reported distance is off", m, h);
  if (!isFinite(normal) || std::fabs(length(normal) - 1.0) > 1e-12) fail(stats, "normal not unit", m, h);
  // The closest points from the reported weights are at the reported distance, and the normal
  // points from the second primitive's point to the first's when they are clearly apart (in long
  // double, so that points far from the origin keep their small differences).
  const auto at = [&](int i) { return lerpR(m[i].start, m[i].end, fraction); };
  RVec gap;
  if (edges) {
    if (!(ee.a >= 0 && ee.a <= 1 && ee.b >= 0 && ee.b <= 1)) fail(stats, "edge parameters outside [0, 1]", m, h);
    gap = (at(0) + (at(1) - at(0)) * ee.a) - (at(2) + (at(3) - at(2)) * ee.b);
  } else {
    const double sum = vt.weight[0] + vt.weight[1] + vt.weight[2];
    if (std::fabs(sum - 1.0) > 1e-14 || std::min({vt.weight[0], vt.weight[1], vt.weight[2]}) < 0.0) {
      fail(stats, "weights not barycentric", m, h);
    }
    gap = at(0) - (at(1) + (at(2) - at(1)) * vt.weight[1] + (at(3) - at(1)) * vt.weight[2]);  // relative to a corner
  }
  const Vec3 between{static_cast<double>(gap.x), static_cast<double>(gap.y), static_cast<double>(gap.z)};
  if (std::fabs(length(between) - d) > 1e-12 * scale) fail(stats, "weights off the closest points", m, h);
  if (d > 1e-6 * scale && length(between / length(between) - normal) > 1e-6) {
    fail(stats, "normal not from the second primitive toward the first", m, h);
  }
}

// A random pair of the given family. Families: 0 all four corners moving independently, 1 the
// triangle (or the second edge) moving rigidly by a translation, 2 degenerate primitives
// (collinear or coincident corners, zero-length edges), 3 thickness set just above or below the
// sampled closest approach (grazing), 4 a constructed crossing (thickness 0 or not), 5 family 0
// or 3 made a thousand times smaller and moved a thousand away from the origin, or made a
// thousand times larger (the tolerance follows the pair, not the coordinates).
void randomCase(Random& random, bool edges, int family, Motion m[4], double& h, double& crossing) {
  static const double kThickness[] = {0.0, 0.01, 0.1, 0.4};
  static const double kTravel[] = {0.05, 0.5, 2.0, 6.0};
  const double travel = kTravel[random.below(4)];
  h = kThickness[random.below(4)];
  crossing = -1.0;
  for (int i = 0; i < 4; ++i) m[i] = {random.point(-1, 1), {}};
  for (int i = 0; i < 4; ++i) m[i].end = m[i].start + random.point(-travel, travel);
  if (family == 1) {
    const Vec3 shift = random.point(-travel, travel);
    for (int i = edges ? 2 : 1; i < 4; ++i) m[i].end = m[i].start + shift;
  }
  if (family == 2) {
    const int which = static_cast<int>(random.below(3));
    if (edges) {
      if (which == 0) m[1] = m[0];
      if (which == 1) m[3] = m[2];
      if (which == 2) {  // parallel, the second edge a scaled copy
        const double k = random.uniform(-2, 2);
        m[3] = {m[2].start + (m[1].start - m[0].start) * k, m[2].end + (m[1].end - m[0].end) * k};
      }
    } else {
      if (which == 0) m[2] = m[1];
      if (which == 1) m[1] = m[2] = m[3];
      if (which == 2) {
        const double k = random.uniform(-1, 2);
        m[3] = {m[1].start + (m[2].start - m[1].start) * k, m[1].end + (m[2].end - m[1].end) * k};
      }
    }
  }
  if (family == 5) {
    const bool small = random.below(2) == 0;
    const double factor = small ? 1e-3 : 1e3;
    const Vec3 offset = small ? Vec3{1000.0, -2000.0, 500.0} : Vec3{};
    for (int i = 0; i < 4; ++i) m[i] = {m[i].start * factor + offset, m[i].end * factor + offset};
    h *= factor;
  }
  if (family == 3 || (family == 5 && random.below(2) == 0)) {
    double minimum = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= kSamples; ++k) {
      const double s = static_cast<double>(k) / kSamples;
      minimum = std::min(minimum, edges ? eeDistance(m, s) : vtDistance(m, s));
    }
    static const double kOffset[] = {-1e-2, -1e-4, -1e-6, 1e-6, 1e-4, 1e-2};
    h = minimum / (1.0 + kOffset[random.below(6)]);
  }
  if (family == 4) {
    // Place the first primitive so that its point (weights w) meets the second's point (weights
    // u) at s_c, each moving with its own corner velocities.
    crossing = random.uniform(0, 1);
    if (random.below(2) == 0) h = 0.0;
    if (edges) {
      const double a = random.uniform(0, 1), b = random.uniform(0, 1);
      const Vec3 meet = m[2].at(crossing) + (m[3].at(crossing) - m[2].at(crossing)) * b;
      const Vec3 direction = random.point(-1, 1);
      const Vec3 p0 = meet - direction * a, p1 = meet + direction * (1 - a);
      const Vec3 v0 = random.point(-travel, travel), v1 = random.point(-travel, travel);
      m[0] = {p0 - v0 * crossing, p0 + v0 * (1 - crossing)};
      m[1] = {p1 - v1 * crossing, p1 + v1 * (1 - crossing)};
    } else {
      const double u = random.uniform(0, 1), v = random.uniform(0, 1 - u);
      const Vec3 meet = m[1].at(crossing) * (1 - u - v) + m[2].at(crossing) * u + m[3].at(crossing) * v;
      const Vec3 velocity = random.point(-travel, travel);
      m[0] = {meet - velocity * crossing, meet + velocity * (1 - crossing)};
    }
  }
}

void runRandom(bool edges, uint32_t seed, int perFamily, Stats& total) {
  Random random(seed);
  for (int family = 0; family < 6; ++family) {
    Stats stats;
    for (int n = 0; n < perFamily; ++n) {
      Motion m[4];
      double h = 0.0, crossing = -1.0;
      randomCase(random, edges, family, m, h, crossing);
      check(m, edges, h, crossing, stats);
    }
    std::printf(
        "  %s family %d: %d cases, %d contacts, (a) checked %d, (d) checked %d, crossings %d, stalls %d, "
        "steps mean %.2f max %d, %.3f us per call\n",
        edges ? "edge-edge" : "vertex-triangle", family, stats.cases, stats.contacts, stats.checkedA, stats.checkedD,
        stats.crossings, stats.stalls, static_cast<double>(stats.steps) / stats.cases, stats.maxSteps,
        1e6 * stats.seconds / stats.cases);
    total.cases += stats.cases;
    total.contacts += stats.contacts;
    total.checkedA += stats.checkedA;
    total.checkedD += stats.checkedD;
    total.crossings += stats.crossings;
    total.failures += stats.failures;
    total.stalls += stats.stalls;
  }
}

TEST(VertexTriangleImpact, RandomAgainstBruteForce) {
  Stats total;
  runRandom(false, 7, kCases, total);
  EXPECT_EQ(total.failures, 0);
  EXPECT_EQ(total.stalls, 0);
  // The cases exercise every assertion many times.
  EXPECT_GT(total.checkedA, kCases * 3 / 4);
  EXPECT_GT(total.checkedD, kCases * 3 / 4);
  EXPECT_EQ(total.crossings, kCases);
}

TEST(EdgeEdgeImpact, RandomAgainstBruteForce) {
  Stats total;
  runRandom(true, 11, kCases, total);
  EXPECT_EQ(total.failures, 0);
  EXPECT_EQ(total.stalls, 0);
  EXPECT_GT(total.checkedA, kCases * 3 / 4);
  EXPECT_GT(total.checkedD, kCases * 3 / 4);
  EXPECT_EQ(total.crossings, kCases);
}

// Resting contact, the costly case for advancement: the pair stays just outside the thickness
// for much of the step while something turns, so a bound that ignores the turning would take
// tiny steps. Each case has a thickness just below (offset > 0: no contact) or just above (offset
// < 0: contact) the closest approach; the answers agree with brute force, in a few steps.
TEST(ContinuousCost, RestingWhileTurning) {
  const double angle = 0.3, c = std::cos(angle), s = std::sin(angle);
  // Rotations by `angle` about the x axis, the y axis, and the line y = -1 in the plane z = 0; the
  // corners move along the chords.
  const auto tiltX = [&](const Vec3& p) { return Motion{p, {p.x, c * p.y - s * p.z, s * p.y + c * p.z}}; };
  const auto tiltY = [&](const Vec3& p) { return Motion{p, {c * p.x + s * p.z, p.y, -s * p.x + c * p.z}}; };
  const auto hinge = [&](const Vec3& p) {
    return Motion{p, {p.x, -1 + c * (p.y + 1) - s * p.z, s * (p.y + 1) + c * p.z}};
  };
  struct Case {
    const char* name;
    bool edges;
    Motion m[4];
  };
  const Case cases[] = {
      // A triangle tilting under a vertex 0.02 above the axis: the gap shrinks to its least at the end.
      {"vertex over a tilting face",
       false,
       {still({0.1, 0, 0.02}), tiltX({-1, -1, 0}), tiltX({1, -1, 0}), tiltX({0, 1, 0})}},
      // A vertex 0.02 beside an edge of a triangle that turns about that edge: constant distance.
      {"vertex beside a hinged edge",
       false,
       {still({0.1, -1.02, 0}), hinge({-1, -1, 0}), hinge({1, -1, 0}), hinge({0, 1, 0})}},
      // An edge 0.02 above another that tilts under it: the gap shrinks to its least at the end.
      {"edge over a tilting edge",
       true,
       {still({0, -0.5, 0.02}), still({0, 0.5, 0.02}), tiltY({-1, 0, 0}), tiltY({1, 0, 0})}},
      // An edge turning about the line of another, 0.02 from it: least at mid-step (the chords).
      {"edge turning about another",
       true,
       {tiltY({-1, 0, 0.02}), tiltY({1, 0, 0.02}), still({0, -1, 0}), still({0, 1, 0})}},
  };
  int failures = 0;
  for (const Case& k : cases) {
    double minimum = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kSamples; ++i) {
      const double f = static_cast<double>(i) / kSamples;
      minimum = std::min(minimum, k.edges ? eeDistance(k.m, f) : vtDistance(k.m, f));
    }
    for (const double offset : {1e-1, 1e-3, 1e-5, 1e-7, -1e-7, -1e-3}) {
      const double h = minimum / (1.0 + offset);
      Stats stats;
      check(k.m, k.edges, h, -1.0, stats);
      failures += stats.failures;
      std::printf("  %s, thickness = closest approach / (1 %+g): %s after %d steps\n", k.name, offset,
                  stats.contacts ? "contact" : "none", stats.maxSteps);
      // A contact must be reported when there is one (offset < 0), and must not be when the
      // closest approach exceeds h + tol (offset 1e-7 is inside the tolerance band: either).
      if (offset < 0 || offset > 1e-6) {
        EXPECT_EQ(stats.contacts, offset < 0 ? 1 : 0) << k.name << " " << offset;
      }
      EXPECT_LE(stats.maxSteps, 20) << k.name << " " << offset;
    }
  }
  EXPECT_EQ(failures, 0);
}

// The same input gives the same answer, bit for bit.
TEST(ContinuousTests, Deterministic) {
  Random random(3);
  for (int n = 0; n < 200; ++n) {
    Motion m[4];
    double h = 0.0, crossing = 0.0;
    randomCase(random, n % 2 == 1, n % 5, m, h, crossing);
    VertexTriangleContact a, b;
    EdgeEdgeContact c, d;
    ASSERT_EQ(vertexTriangleImpact(m[0], m[1], m[2], m[3], h, a), vertexTriangleImpact(m[0], m[1], m[2], m[3], h, b));
    EXPECT_EQ(a.fraction, b.fraction);
    EXPECT_EQ(a.normal, b.normal);
    ASSERT_EQ(edgeEdgeImpact(m[0], m[1], m[2], m[3], h, c), edgeEdgeImpact(m[0], m[1], m[2], m[3], h, d));
    EXPECT_EQ(c.fraction, d.fraction);
    EXPECT_EQ(c.a, d.a);
  }
}

// ---------------------------------------------------------------------------------------------
// Swept boxes.

TEST(SweptBox, HoldsThePrimitiveThroughoutAndIsConservativeForPairs) {
  Random random(5);
  int checked = 0;
  for (int n = 0; n < 2000; ++n) {
    Motion m[4];
    double h = 0.0, crossing = 0.0;
    randomCase(random, n % 2 == 1, n % 5, m, h, crossing);
    const bool edges = n % 2 == 1;
    const Box first = edges ? sweptBox(m[0], m[1], h / 2) : sweptBox(m[0], h / 2);
    const Box second = edges ? sweptBox(m[2], m[3], h / 2) : sweptBox(m[1], m[2], m[3], h / 2);
    for (int k = 0; k <= 100; ++k) {
      const double s = k / 100.0;
      for (int i = 0; i < 4; ++i) {
        const Box& box = (edges ? i < 2 : i < 1) ? first : second;
        const Vec3 p = m[i].at(s);
        const double slack = 1e-15 * (maxAbs(box.lo) + maxAbs(box.hi));  // the rounding of m[i].at(s)
        ASSERT_TRUE(p.x >= box.lo.x - slack && p.y >= box.lo.y - slack && p.z >= box.lo.z - slack &&
                    p.x <= box.hi.x + slack && p.y <= box.hi.y + slack && p.z <= box.hi.z + slack);
      }
      if ((edges ? eeDistance(m, s) : vtDistance(m, s)) <= h) {
        ++checked;
        ASSERT_TRUE(overlaps(first, second)) << describe(m, h);
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

// ---------------------------------------------------------------------------------------------
// BVH.

std::vector<Box> randomBoxes(Random& random, int n, double extent, double size) {
  std::vector<Box> boxes(static_cast<std::size_t>(n));
  for (Box& box : boxes) {
    const Vec3 lo = random.point(0, extent);
    // Mostly small boxes, a few long ones.
    const double k = random.below(20) == 0 ? 8.0 : 1.0;
    box = {lo, lo + Vec3{random.uniform(0, size * k), random.uniform(0, size), random.uniform(0, size)}};
  }
  return boxes;
}

std::vector<PrimitivePair> bruteSelf(const std::vector<Box>& boxes) {
  std::vector<PrimitivePair> out;
  for (uint32_t i = 0; i < boxes.size(); ++i) {
    for (uint32_t j = i + 1; j < boxes.size(); ++j) {
      if (overlaps(boxes[i], boxes[j])) out.push_back({i, j});
    }
  }
  return out;
}

std::vector<PrimitivePair> bruteCross(const std::vector<Box>& a, const std::vector<Box>& b) {
  std::vector<PrimitivePair> out;
  for (uint32_t i = 0; i < a.size(); ++i) {
    for (uint32_t j = 0; j < b.size(); ++j) {
      if (overlaps(a[i], b[j])) out.push_back({i, j});
    }
  }
  return out;
}

// Sweep and prune along x: an independent O(N log N + candidates) reference for large N.
std::vector<PrimitivePair> sweepSelf(const std::vector<Box>& boxes) {
  std::vector<uint32_t> order(boxes.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](uint32_t u, uint32_t w) { return boxes[u].lo.x < boxes[w].lo.x; });
  std::vector<PrimitivePair> out;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (std::size_t j = i + 1; j < order.size() && boxes[order[j]].lo.x <= boxes[order[i]].hi.x; ++j) {
      if (overlaps(boxes[order[i]], boxes[order[j]])) {
        out.push_back({std::min(order[i], order[j]), std::max(order[i], order[j])});
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void moveBoxes(Random& random, std::vector<Box>& boxes, double jitter) {
  for (Box& box : boxes) {
    const Vec3 shift = random.point(-jitter, jitter);
    box.lo += shift;
    box.hi += shift + random.point(0, jitter / 4);
  }
}

TEST(Bvh, PairsEqualBruteForceBeforeAndAfterRefitAndRebuild) {
  Random random(99);
  std::vector<Box> a = randomBoxes(random, 3000, 10.0, 0.5), b = randomBoxes(random, 2500, 10.0, 0.5);
  Bvh ta, tb;
  ta.build(a);
  tb.build(b);
  EXPECT_EQ(ta.degradation(), 1.0);
  for (int round = 0; round < 3; ++round) {
    std::vector<PrimitivePair> self, cross;
    selfOverlapPairs(ta, self);
    overlapPairs(ta, tb, cross);
    const std::vector<PrimitivePair> bruteS = bruteSelf(a), bruteC = bruteCross(a, b);
    EXPECT_GT(bruteS.size(), 500u);
    EXPECT_GT(bruteC.size(), 500u);
    EXPECT_EQ(self, bruteS) << "round " << round;
    EXPECT_EQ(cross, bruteC) << "round " << round;
    // Reversed roles give the same pairs, swapped.
    std::vector<PrimitivePair> reversed;
    overlapPairs(tb, ta, reversed);
    for (PrimitivePair& p : reversed) std::swap(p.a, p.b);
    std::sort(reversed.begin(), reversed.end());
    EXPECT_EQ(reversed, bruteC);
    if (round == 0) {  // move and refit
      moveBoxes(random, a, 0.3);
      moveBoxes(random, b, 0.3);
      ta.refit(a);
      tb.refit(b);
    } else if (round == 1) {  // rebuild over the refitted boxes
      ta.rebuild();
      tb.rebuild();
      EXPECT_EQ(ta.degradation(), 1.0);
    }
  }
}

TEST(Bvh, FilterExcludesExactlyWhatItSays) {
  Random random(17);
  const std::vector<Box> a = randomBoxes(random, 2000, 8.0, 0.5), b = randomBoxes(random, 1500, 8.0, 0.5);
  Bvh ta, tb;
  ta.build(a);
  tb.build(b);
  bool ordered = true;
  const auto exclude = [&](uint32_t i, uint32_t j) {
    ordered = ordered && i < j;
    return (i + j) % 3 == 0;
  };
  std::vector<PrimitivePair> self;
  selfOverlapPairs(ta, exclude, self);
  EXPECT_TRUE(ordered);  // the self filter sees each pair as (a, b) with a < b
  std::vector<PrimitivePair> expected;
  for (const PrimitivePair& p : bruteSelf(a)) {
    if ((p.a + p.b) % 3 != 0) expected.push_back(p);
  }
  EXPECT_EQ(self, expected);
  const auto excludeCross = [](uint32_t i, uint32_t j) { return i == j || (i * 7 + j) % 5 == 0; };
  std::vector<PrimitivePair> cross;
  overlapPairs(ta, tb, excludeCross, cross);
  expected.clear();
  for (const PrimitivePair& p : bruteCross(a, b)) {
    if (!excludeCross(p.a, p.b)) expected.push_back(p);
  }
  EXPECT_EQ(cross, expected);
  // Dense (every primitive overlaps many), with neighbours in index excluded, as mesh neighbours
  // would be: every index, 0 included, has pairs kept and pairs dropped.
  const std::vector<Box> dense = randomBoxes(random, 400, 1.0, 1.0);
  Bvh td;
  td.build(dense);
  const auto neighbours = [](uint32_t i, uint32_t j) { return j - i <= 2; };
  std::vector<PrimitivePair> kept;
  selfOverlapPairs(td, neighbours, kept);
  expected.clear();
  std::size_t dropped = 0;
  for (const PrimitivePair& p : bruteSelf(dense)) {
    if (neighbours(p.a, p.b)) {
      ++dropped;
    } else {
      expected.push_back(p);
    }
  }
  EXPECT_GT(dropped, 100u);
  EXPECT_EQ(kept, expected);
}

TEST(Bvh, OutputIsSortedAppendedAndIdenticalOnTwoRuns) {
  Random random(23);
  const std::vector<Box> boxes = randomBoxes(random, 3000, 10.0, 0.6);
  std::vector<PrimitivePair> first{{7, 7}}, second{{7, 7}};  // existing content stays in front
  Bvh t1, t2;
  t1.build(boxes);
  t2.build(boxes);
  selfOverlapPairs(t1, first);
  selfOverlapPairs(t2, second);
  ASSERT_GT(first.size(), 100u);
  EXPECT_EQ(first.front(), (PrimitivePair{7, 7}));
  EXPECT_TRUE(std::is_sorted(first.begin() + 1, first.end()));
  EXPECT_TRUE(std::adjacent_find(first.begin() + 1, first.end()) == first.end());  // each pair once
  EXPECT_EQ(first, second);
  // The tree is a function of the boxes alone.
  ASSERT_EQ(t1.nodes().size(), t2.nodes().size());
  for (uint32_t k = 0; k < t1.primitiveCount(); ++k) EXPECT_EQ(t1.primitiveAt(k), t2.primitiveAt(k));
}

TEST(Bvh, DegradationTracksLooseningNotMotion) {
  Random random(31);
  std::vector<Box> boxes = randomBoxes(random, 4000, 10.0, 0.3);
  Bvh tree;
  tree.build(boxes);
  // Moving the whole set and scaling it up: the tree is as good as new.
  for (Box& box : boxes) box = {box.lo * 3.0 + Vec3{5, -2, 1}, box.hi * 3.0 + Vec3{5, -2, 1}};
  tree.refit(boxes);
  EXPECT_NEAR(tree.degradation(), 1.0, 1e-9);
  EXPECT_FALSE(tree.needsRebuild());
  // Scattering the primitives: every node spreads over the whole set.
  Random scatter(32);
  std::vector<Box> scattered = randomBoxes(scatter, 4000, 30.0, 0.9);
  tree.refit(scattered);
  EXPECT_GT(tree.degradation(), 2.0);
  EXPECT_TRUE(tree.needsRebuild());
  std::vector<PrimitivePair> pairs;
  selfOverlapPairs(tree, pairs);
  EXPECT_EQ(pairs, bruteSelf(scattered));  // loose, still exact
  tree.rebuild();
  EXPECT_EQ(tree.degradation(), 1.0);
  pairs.clear();
  selfOverlapPairs(tree, pairs);
  EXPECT_EQ(pairs, bruteSelf(scattered));
}

TEST(Bvh, EdgeCases) {
  Bvh empty, one, tree;
  empty.build(std::vector<Box>{});
  std::vector<PrimitivePair> pairs;
  selfOverlapPairs(empty, pairs);
  one.build(std::vector<Box>{{{0, 0, 0}, {1, 1, 1}}});
  selfOverlapPairs(one, pairs);
  overlapPairs(one, empty, pairs);
  overlapPairs(empty, one, pairs);
  EXPECT_TRUE(pairs.empty());
  overlapPairs(one, one, pairs);
  EXPECT_EQ(pairs, (std::vector<PrimitivePair>{{0, 0}}));
  // 300 identical boxes: all centroids tie, the split goes by index; every pair overlaps.
  const std::vector<Box> same(300, Box{{1, 1, 1}, {2, 2, 2}});
  tree.build(same);
  pairs.clear();
  selfOverlapPairs(tree, pairs);
  EXPECT_EQ(pairs.size(), 300u * 299u / 2u);
  EXPECT_EQ(pairs, bruteSelf(same));
  // Points (zero-size boxes) on a line: touching counts as overlapping.
  std::vector<Box> line;
  for (int i = 0; i < 50; ++i) line.push_back({{i * 0.5, 0, 0}, {i * 0.5 + 0.5, 0, 0}});
  tree.build(line);
  pairs.clear();
  selfOverlapPairs(tree, pairs);
  EXPECT_EQ(pairs, bruteSelf(line));
  EXPECT_EQ(pairs.size(), 49u);
}

// 100k primitives: the traversal's stack grows on the heap; the pair set equals sweep and prune.
TEST(Bvh, HundredThousandPrimitives) {
  Random random(41);
  std::vector<Box> boxes = randomBoxes(random, 100000, 20.0, 0.08);
  Bvh tree;
  auto start = std::chrono::steady_clock::now();
  tree.build(boxes);
  const double buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<PrimitivePair> pairs;
  start = std::chrono::steady_clock::now();
  selfOverlapPairs(tree, pairs);
  const double querySeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(pairs, sweepSelf(boxes));
  moveBoxes(random, boxes, 0.05);
  start = std::chrono::steady_clock::now();
  tree.refit(boxes);
  const double refitSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  pairs.clear();
  selfOverlapPairs(tree, pairs);
  EXPECT_EQ(pairs, sweepSelf(boxes));
  // All on one line (a long thin body): still exact.
  std::vector<Box> chain(100000);
  for (std::size_t i = 0; i < chain.size(); ++i) {
    const double x = 0.01 * static_cast<double>(i);
    chain[i] = {{x, 0, 0}, {x + 0.015, 0.01, 0.01}};
  }
  tree.build(chain);
  pairs.clear();
  selfOverlapPairs(tree, pairs);
  EXPECT_EQ(pairs, sweepSelf(chain));
  std::printf("  100k boxes: build %.1f ms, self query %.1f ms (%zu pairs), refit %.2f ms\n", 1e3 * buildSeconds,
              1e3 * querySeconds, pairs.size(), 1e3 * refitSeconds);
}

}  // namespace
}  // namespace springy

// springy: the geometry of body-body and self contact (issue 16): closest points between
// primitives and continuous (swept) proximity tests over one step.
//
// A step moves every vertex along a straight line from its position at the start (s = 0) to its
// position at the end (s = 1). Two primitives, a vertex and a triangle or two edges, are in
// contact when they come within a distance `thickness` >= 0 of each other; the continuous tests
// below return the EARLIEST such s, so that nothing passes through anything between two steps,
// however fast it moves. Only the geometry is here: the caller (the time step) decides what to
// do with a contact. Nothing here allocates.
//
// Method: conservative advancement (Mirtich 1996, PhD thesis "Impulse-based dynamic simulation
// of rigid body systems", UC Berkeley): advance s by an interval over which the pair provably
// stays farther apart than the thickness, recompute the distance there, repeat until the
// distance is within the thickness (a contact) or s passes 1 (none). What makes the advances
// long is the bounds, all derived in contact_geometry.cpp from one observation: the set of differences
// r = (point of the first primitive) - (point of the second) at fraction s is the convex hull of
// a few corners r_k(s) (3 for a vertex and a triangle, 4 for two edges), and each corner moves
// linearly in s. So, for any direction n, min over the set of n.r is the minimum over the corners
// of linear functions of s, and it bounds the distance from below. In order of cost:
//  - n fixed along the closest difference vector (the supporting plane of the set nearest the
//    origin): never a shorter step than the classic (distance - thickness) / (largest relative
//    corner speed), and exact for a pair that translates straight at each other;
//  - n turning with the closest feature, n(s) = c + (s - s0) dc/ds: quadratics in s instead of
//    lines, which keeps advances long when the pair passes close while turning (grazing);
//  - the moving plane of the triangle (of the parallelogram of two edges), which holds the whole
//    set: its distance |f| / |N| with f(s) the cubic whose roots are the coplanarity times of
//    Bridson, Fedkiw & Anderson 2002 (§4) gives a quartic whose first root is the step; all but
//    exact for a vertex coming at the face of a turning triangle, or an edge at a turning edge.
// Before the first query, two fixed directions are tried over the whole step (the normal of the set's
// plane at s = 0, and the sum of its corners): along a fixed direction the bound is linear in s
// per corner, so two values per corner decide it. Most pairs that pass the boxes but do not touch
// (a vertex over a face, edges over edges) end there, without a closest-point query.
// Why not the coplanarity cubic alone, as Bridson et al. do? It finds the instants at which the
// four points are coplanar and tests proximity there; a vertex that comes within the thickness
// of a triangle and leaves again without ever being coplanar with it has no such instant, so
// with a thickness it misses contacts. Here the cubic is one bound among others, used only to
// prove that nothing happens before its root.
//
// Guarantees of vertexTriangleImpact and edgeEdgeImpact (h = thickness, tol = contactTolerance):
//  - Conservative: if the primitives come within h of each other at some s in [0, 1], a contact
//    is reported at a fraction no later than the first such s. (Every skipped interval is proven
//    to keep the distance > h + tol / 2, in exact arithmetic on the computed corners; the margin
//    tol / 2 is far above the rounding, about 1e-16 of the corners' size.)
//  - Earliest within tolerance: the distance is > h + tol / 2 at every s before the reported
//    fraction and <= h + tol at it (so a report lands at most tol / (2 approach speed) before
//    the exact first contact). A pair already within h + tol at s = 0 reports s = 0.
//  - Deterministic: plain double arithmetic in a fixed order, no randomness, no state.
//  - Never NaN for finite input whose products of coordinates do not overflow, degenerate
//    (zero-area, zero-length, parallel) primitives included.
//  - Cost: one closest-point query per advance, plus the bounds; none for a pair cleared by the
//    two fixed directions. Measured on random pairs (tests/test_contact_geometry.cpp, and soaks
//    of 640,000 cases, before the fixed directions were added): a miss took 1.1-1.5 queries on
//    average, a crossing 2.6 (at most 13), a grazing pass whose closest approach is within 1e-6
//    to 1e-2 of the thickness 3.4 (at most 41); 0.2-1.5 us a call on one core of the development
//    VM. With them, the test's families of mostly missing pairs take 0.4-1.0 queries on average.
//    After kMaxAdvanceSteps queries, or if no advance can be proven safe (round-off beyond the
//    margin, which the tests never produced), a contact is reported at the current fraction:
//    still no later than the first contact, but `distance`, the true distance there, is then
//    above h + tol, which a caller can check.
#pragma once

#include <cstdint>

#include "sim/vec3.h"

namespace springy {

// A vertex moving linearly over one step: at fraction s it is at start + s (end - start).
struct Motion {
  Vec3 start, end;
  Vec3 at(double s) const { return start + (end - start) * s; }
};

// An axis-aligned box, for the broad phase.
struct Box {
  Vec3 lo, hi;
};

inline bool overlaps(const Box& a, const Box& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
         b.lo.z <= a.hi.z;
}
inline Box merged(const Box& a, const Box& b) { return {componentMin(a.lo, b.lo), componentMax(a.hi, b.hi)}; }
inline double surfaceArea(const Box& b) {
  const Vec3 d = b.hi - b.lo;
  return 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
}

// Swept boxes: the box of a primitive's corners at s = 0 and s = 1 (which holds the primitive
// at every s in between, as positions move linearly), grown by `margin` on every side. For a
// pair tested with thickness h, give both primitives margin h / 2: two primitives can come within
// h of each other during the step only if their boxes overlap.
Box sweptBox(const Motion& x, double margin);
Box sweptBox(const Motion& p, const Motion& q, double margin);
Box sweptBox(const Motion& a, const Motion& b, const Motion& c, double margin);

// Closest point of triangle (a, b, c) to p: weight[0] a + weight[1] b + weight[2] c, weights in
// [0, 1] summing to 1. Any triangle, degenerate (collinear or coincident corners) included.
struct PointTriangleClosest {
  double distanceSquared = 0.0;
  double weight[3] = {1.0, 0.0, 0.0};
};
PointTriangleClosest closestPointTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Closest points of the segments p0 p1 and q0 q1: p0 + s (p1 - p0) and q0 + t (q1 - q0), s and
// t in [0, 1]. Parallel, overlapping and zero-length segments included (for parallel ones any
// closest pair may be returned).
struct SegmentSegmentClosest {
  double distanceSquared = 0.0;
  double s = 0.0, t = 0.0;
};
SegmentSegmentClosest closestSegmentSegment(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1);

// Tolerance of the continuous tests: a part relative to the thickness and one relative to the
// pair's `scale`, the largest coordinate of any difference of a corner of the first primitive and
// one of the second, at the start or at the end; the latter stays far above the rounding of the
// distance computations (about 1e-16 scale) so that the margins in the proofs hold. [m]
constexpr double kContactRelativeTolerance = 1e-7;
constexpr double kContactAbsoluteTolerance = 1e-10;
inline double contactTolerance(double thickness, double scale) {
  return kContactRelativeTolerance * thickness + kContactAbsoluteTolerance * scale;
}
// Closest-point queries after which a pair is reported in contact at the current fraction.
constexpr int kMaxAdvanceSteps = 200;

struct VertexTriangleContact {
  double fraction = 0.0;               // s in [0, 1]
  double weight[3] = {1.0, 0.0, 0.0};  // barycentric weights of the triangle's closest point at s
  Vec3 normal;                         // unit, from the triangle toward the vertex (the side it came from)
  double distance = 0.0;               // between the two at s [m]
  int steps = 0;                       // closest-point queries made (cost), set also on a miss
};

struct EdgeEdgeContact {
  double fraction = 0.0;  // s in [0, 1]
  double a = 0.0;         // closest point on the first edge at s: p0 + a (p1 - p0)
  double b = 0.0;         // closest point on the second edge at s: q0 + b (q1 - q0)
  Vec3 normal;            // unit, from the second edge toward the first
  double distance = 0.0;  // between the two at s [m]
  int steps = 0;          // closest-point queries made (cost), set also on a miss
};

// A vertex x against the triangle (a, b, c), all moving linearly over the step: whether they come
// within `thickness` (>= 0) of each other, and if so the earliest fraction (guarantees above).
bool vertexTriangleImpact(const Motion& x, const Motion& a, const Motion& b, const Motion& c, double thickness,
                          VertexTriangleContact& contact);

// The edge p0 p1 against the edge q0 q1, all moving linearly over the step (guarantees above).
bool edgeEdgeImpact(const Motion& p0, const Motion& p1, const Motion& q0, const Motion& q1, double thickness,
                    EdgeEdgeContact& contact);

}  // namespace springy

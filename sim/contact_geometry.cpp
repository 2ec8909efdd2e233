#include "sim/contact_geometry.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace springy {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

double clamp01(double v) { return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v); }
// std::fmax, inline: the larger of a and b, the other one if either is NaN. (GCC calls libm's fmax
// unless NaNs are ruled out; those calls were 4% of the contact stage.)
double largerOf(double a, double b) { return b > a || a != a ? b : a; }

// Parameter in [0, 1] of the point of the segment a + t e closest to p (Ericson 2005, §5.1.2).
// A zero-length segment gives 0; the quotient of finite numbers is never NaN otherwise.
double closestOnSegment(const Vec3& p, const Vec3& a, const Vec3& e) {
  const double ee = dot(e, e);
  if (!(ee > 0.0)) return 0.0;
  return clamp01(dot(p - a, e) / ee);
}

PointTriangleClosest pointTriangleResult(const Vec3& p, const Vec3& q, double u, double v, double w) {
  PointTriangleClosest out;
  out.distanceSquared = lengthSquared(q - p);
  out.weight[0] = u;
  out.weight[1] = v;
  out.weight[2] = w;
  return out;
}

// The closest point on the triangle's three edges: exact whenever the closest point of the
// triangle lies on its boundary, which is always the case for a degenerate triangle.
PointTriangleClosest closestOnEdges(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const double tab = closestOnSegment(p, a, b - a), tbc = closestOnSegment(p, b, c - b),
               tca = closestOnSegment(p, c, a - c);
  PointTriangleClosest best = pointTriangleResult(p, a + (b - a) * tab, 1.0 - tab, tab, 0.0);
  const PointTriangleClosest onBc = pointTriangleResult(p, b + (c - b) * tbc, 0.0, 1.0 - tbc, tbc);
  const PointTriangleClosest onCa = pointTriangleResult(p, c + (a - c) * tca, tca, 0.0, 1.0 - tca);
  if (onBc.distanceSquared < best.distanceSquared) best = onBc;
  if (onCa.distanceSquared < best.distanceSquared) best = onCa;
  return best;
}

}  // namespace

Box sweptBox(const Motion& x, double margin) {
  const Vec3 m{margin, margin, margin};
  return {componentMin(x.start, x.end) - m, componentMax(x.start, x.end) + m};
}

Box sweptBox(const Motion& p, const Motion& q, double margin) {
  const Box a = sweptBox(p, margin), b = sweptBox(q, margin);
  return merged(a, b);
}

Box sweptBox(const Motion& a, const Motion& b, const Motion& c, double margin) {
  return merged(sweptBox(a, b, margin), sweptBox(c, margin));
}

// Ericson 2005, §5.1.5 (ClosestPtPointTriangle): classify p against the Voronoi regions of the
// corners, then of the edges, else it projects into the face. Two changes for robustness:
//  - the scaled signed areas va, vb, vc are computed as triple products n . ((b - p) x (c - p))
//    etc. rather than as the book's differences of products of dot products (equal by Lagrange's
//    identity): the cross products lose less to cancellation on slivers;
//  - every division is guarded: a point on an edge comes from closestOnSegment, and the face
//    case is taken only when all three areas are >= 0 with a positive sum. Anything else (a
//    degenerate triangle, or round-off contradicting the region tests) falls back to the best of
//    the three edges, which is exact there. For a sliver the areas' signs cannot be trusted to
//    pick an edge: the best of the edges and the face point is taken.
PointTriangleClosest closestPointTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return pointTriangleResult(p, a, 1.0, 0.0, 0.0);  // corner a
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return pointTriangleResult(p, b, 0.0, 1.0, 0.0);  // corner b
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return pointTriangleResult(p, c, 0.0, 0.0, 1.0);  // corner c

  // A degenerate or sliver triangle (sin^2 of the angle at a below 1e-8): the signed areas are
  // too small for their signs to pick an edge, so take the best of the three edges and, if the
  // areas put p over the face, of the face point.
  const Vec3 n = cross(ab, ac);
  const double nn = dot(n, n);
  const bool sliver = !(nn > 1e-8 * dot(ab, ab) * dot(ac, ac));
  const double va = dot(n, cross(b - p, c - p)), vb = dot(n, cross(c - p, a - p)), vc = dot(n, cross(a - p, b - p));
  if (!sliver) {
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {  // edge ab
      const double t = closestOnSegment(p, a, ab);
      return pointTriangleResult(p, a + ab * t, 1.0 - t, t, 0.0);
    }
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {  // edge ac
      const double t = closestOnSegment(p, a, ac);
      return pointTriangleResult(p, a + ac * t, 1.0 - t, 0.0, t);
    }
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {  // edge bc
      const double t = closestOnSegment(p, b, c - b);
      return pointTriangleResult(p, b + (c - b) * t, 0.0, 1.0 - t, t);
    }
  }
  const double area2 = va + vb + vc;  // = |n|^2 in exact arithmetic
  const bool overFace = va >= 0.0 && vb >= 0.0 && vc >= 0.0 && area2 > 0.0;
  if (!overFace) return closestOnEdges(p, a, b, c);
  const double v = vb / area2, w = vc / area2;
  const double u = largerOf(0.0, 1.0 - v - w);
  const PointTriangleClosest face = pointTriangleResult(p, a + ab * v + ac * w, u, v, w);
  if (sliver) {
    const PointTriangleClosest edge = closestOnEdges(p, a, b, c);
    if (edge.distanceSquared <= face.distanceSquared) return edge;
  }
  return face;
}

// Ericson 2005, §5.1.9 (ClosestPtSegmentSegment): minimize over the two lines, clamp s to
// [0, 1], take t for that s and, if t had to be clamped, recompute s for the clamped t. Zero-length
// segments are detected exactly (a quotient of finite numbers by a positive one is finite, and is
// then clamped, so no epsilon is needed for them). Unlike the book, the unclamped s is computed
// as n . (d2 x r) / |n|^2 with n = d1 x d2, equal to its (b f - c e) / (a e - b^2) by Lagrange's
// identity: for nearly parallel segments the cross products keep a relative error of eps / sin
// rather than eps / sin^2, so the distance stays accurate to about eps |r|. Parallel (scale-aware:
// sin^2 below 1e-30) gives the book's s = 0, from which the clamping finds a closest pair.
SegmentSegmentClosest closestSegmentSegment(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  double s = 0.0, t = 0.0;
  if (!(a > 0.0) && !(e > 0.0)) {
    // Both points.
  } else if (!(a > 0.0)) {
    t = clamp01(f / e);
  } else {
    const double c = dot(d1, r);
    if (!(e > 0.0)) {
      s = clamp01(-c / a);
    } else {
      const double b = dot(d1, d2);
      const Vec3 n = cross(d1, d2);
      const double nn = dot(n, n);
      if (nn > 1e-30 * a * e) s = clamp01(dot(n, cross(d2, r)) / nn);
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = clamp01(-c / a);
      } else if (t > 1.0) {
        t = 1.0;
        s = clamp01((b - c) / a);
      }
    }
  }
  SegmentSegmentClosest out;
  out.s = s;
  out.t = t;
  out.distanceSquared = lengthSquared(r + d1 * s - d2 * t);
  return out;
}

namespace {

// The difference set of a pair at fraction s: every difference (point of the first primitive) -
// (point of the second) is a convex combination of the corners r_k(s) = r0[k] + s v[k]. A vertex
// x and a triangle y0 y1 y2: r_k = x - y_k with the barycentric weights of the triangle point. Two
// edges: r_(i + 2j) = p_i - q_j with the bilinear weights of the two edge parameters.
struct Corners {
  bool edges = false;
  Vec3 r0[4], v[4];
  int count() const { return edges ? 4 : 3; }
  Vec3 at(int k, double s) const { return r0[k] + v[k] * s; }
};

// The closest difference vector at some s, with the corners of the feature it lies on (1: a
// corner, 2: an edge of the set, 3: its plane) and its weights.
struct Closest {
  Vec3 c;
  double distance = 0.0;
  double w[3] = {1.0, 0.0, 0.0};  // vertex-triangle: barycentric weights; edges: w[0] = a, w[1] = b
  int feature[3] = {0, 0, 0};
  int featureSize = 1;
};

Closest closestAt(const Corners& k, double s) {
  Closest out;
  if (!k.edges) {
    const Vec3 r0 = k.at(0, s), r1 = k.at(1, s), r2 = k.at(2, s);
    const PointTriangleClosest q = closestPointTriangle(Vec3{}, r0, r1, r2);
    out.c = r0 + (r1 - r0) * q.weight[1] + (r2 - r0) * q.weight[2];
    out.featureSize = 0;
    for (int i = 0; i < 3; ++i) {
      out.w[i] = q.weight[i];
      if (q.weight[i] != 0.0) out.feature[out.featureSize++] = i;
    }
    if (out.featureSize == 0) out.featureSize = 1;  // cannot happen (the weights sum to 1); kept safe
  } else {
    // Edge p relative to q0: P0 = r_00, P1 = r_10; edge q: Q0 = 0, Q1 = q1 - q0 = r_00 - r_01.
    const Vec3 p0 = k.at(0, s), p1 = k.at(1, s), q1 = p0 - k.at(2, s);
    const SegmentSegmentClosest q = closestSegmentSegment(p0, p1, Vec3{}, q1);
    out.c = p0 + (p1 - p0) * q.s - q1 * q.t;
    out.w[0] = q.s;
    out.w[1] = q.t;
    out.w[2] = 0.0;
    const bool aEnd = q.s == 0.0 || q.s == 1.0, bEnd = q.t == 0.0 || q.t == 1.0;
    const int i = q.s == 1.0 ? 1 : 0, j = q.t == 1.0 ? 1 : 0;
    if (aEnd && bEnd) {
      out.feature[0] = i + 2 * j;
      out.featureSize = 1;
    } else if (aEnd) {  // an end of p against the inside of q
      out.feature[0] = i;
      out.feature[1] = i + 2;
      out.featureSize = 2;
    } else if (bEnd) {  // an end of q against the inside of p
      out.feature[0] = 2 * j;
      out.feature[1] = 2 * j + 1;
      out.featureSize = 2;
    } else {  // inside both: the plane of the parallelogram
      out.feature[0] = 0;
      out.feature[1] = 1;
      out.feature[2] = 2;
      out.featureSize = 3;
    }
  }
  out.distance = length(out.c);
  return out;
}

// d/ds of the difference vector with the weights held fixed.
Vec3 frozenRate(const Corners& k, const Closest& q) {
  if (!k.edges) return k.v[0] * q.w[0] + k.v[1] * q.w[1] + k.v[2] * q.w[2];
  const double a = q.w[0], b = q.w[1];
  return k.v[0] * ((1.0 - a) * (1.0 - b)) + k.v[1] * (a * (1.0 - b)) + k.v[2] * ((1.0 - a) * b) + k.v[3] * (a * b);
}

// d/ds of the closest vector of the origin to the affine hull of the feature's corners (a
// corner, a line, a plane), kept fixed at the feature found at s: where the closest point stays
// on that feature this is the rate of the closest vector itself. Any value is a valid input to
// the advancement bound (it only steers the direction); a degenerate feature falls back to the
// frozen-weight rate. Derivatives of c = r_i + t e, t = -(e . r_i) / (e . e) (a line) and of
// c = (g / m) N, N = e1 x e2, g = N . r_i, m = N . N (a plane), by the product and quotient rules.
Vec3 closestRate(const Corners& k, const Closest& q, double s) {
  const int i = q.feature[0];
  const Vec3 ri = k.at(i, s), vi = k.v[i];
  if (q.featureSize == 1) return vi;
  if (q.featureSize == 2) {
    const int j = q.feature[1];
    const Vec3 e = k.at(j, s) - ri, ed = k.v[j] - vi;
    const double ee = dot(e, e), er = dot(e, ri);
    if (!(ee > 0.0)) return frozenRate(k, q);
    const double t = -er / ee;
    const double td = -((dot(ed, ri) + dot(e, vi)) * ee - er * 2.0 * dot(e, ed)) / (ee * ee);
    return vi + e * td + ed * t;
  }
  const Vec3 e1 = k.at(q.feature[1], s) - ri, e2 = k.at(q.feature[2], s) - ri;
  const Vec3 e1d = k.v[q.feature[1]] - vi, e2d = k.v[q.feature[2]] - vi;
  const Vec3 n = cross(e1, e2), nd = cross(e1d, e2) + cross(e1, e2d);
  const double m = dot(n, n);
  if (!(m > 1e-20 * dot(e1, e1) * dot(e2, e2))) return frozenRate(k, q);
  const double g = dot(n, ri), gd = dot(nd, ri) + dot(n, vi), md = 2.0 * dot(n, nd);
  return n * (gd / m - g * md / (m * m)) + nd * (g / m);
}

// Smallest tau > 0 with alpha + beta tau + gamma tau^2 = 0 for alpha > 0 (infinity if none). The
// roots are q / gamma and alpha / q with q = -(beta + sign(beta) sqrt(beta^2 - 4 alpha gamma)) / 2,
// which avoids cancellation (Press et al. 2007, Numerical Recipes 3rd ed., §5.6).
double firstPositiveRoot(double alpha, double beta, double gamma) {
  if (gamma == 0.0) return beta < 0.0 ? alpha / -beta : kInfinity;
  const double disc = beta * beta - 4.0 * alpha * gamma;
  if (disc < 0.0) return kInfinity;      // then gamma > 0: no real root, positive throughout
  if (!std::isfinite(disc)) return 0.0;  // overflow: prove nothing
  const double q = -0.5 * (beta + std::copysign(std::sqrt(disc), beta));
  const double r1 = q / gamma, r2 = q != 0.0 ? alpha / q : kInfinity;
  double root = kInfinity;
  if (r1 > 0.0) root = r1;
  if (r2 > 0.0 && r2 < root) root = r2;
  return root;
}

// How far past s the pair provably stays farther apart than h, using a direction that turns
// linearly, n(tau) = n0 + tau n1 (tau = fraction past s).
//
// Derivation (ours). Every difference vector at s + tau is a convex combination of the corners
// r_k(s + tau) = r_k + tau v_k, so n(tau) . r >= min_k n(tau) . r_k(s + tau), and |r| >=
// n(tau) . r / |n(tau)| (Cauchy-Schwarz). Bound |n(tau)| = sqrt(|n0|^2 + 2 tau n0.n1 + tau^2 |n1|^2)
// from above by U(tau) = |n0| + tau n0.n1 / |n0| + tau^2 |n1|^2 / (2 |n0|) (sqrt(a^2 + x) <=
// a + x / (2a)). Then the distance exceeds h wherever every
//   Q_k(tau) = n(tau) . r_k(s + tau) - h U(tau)
//            = (n0.r_k - h |n0|) + tau (n0.v_k + n1.r_k - h n0.n1 / |n0|) + tau^2 (n1.v_k - h |n1|^2 / (2 |n0|))
// is positive: up to the first positive root of the quadratics. With n0 = c (the closest vector
// at s) Q_k(0) >= |c| (|c| - h) > 0, since c . r >= |c|^2 over the set (c is its point nearest
// the origin). n1 = 0 makes the Q_k linear: the step to where the set's lowest corner, measured
// along c, reaches h; that step is never shorter than the classic (|c| - h) / max_k |v_k|
// (Mirtich 1996), as c.r_k / |c| >= |c| and c.v_k / |c| >= -|v_k|.
double advanceBound(const Corners& k, double s, const Vec3& n0, const Vec3& n1, double h) {
  const double n0Length = length(n0);
  if (!isFinite(n0) || !isFinite(n1) || !(n0Length > 0.0)) return 0.0;  // proves nothing
  const double n01 = dot(n0, n1) / n0Length, n11 = dot(n1, n1) / (2.0 * n0Length);
  double bound = kInfinity;
  for (int i = 0; i < k.count(); ++i) {
    const Vec3 r = k.at(i, s);
    const double alpha = dot(n0, r) - h * n0Length;
    if (!(alpha > 0.0)) return 0.0;
    const double beta = dot(n0, k.v[i]) + dot(n1, r) - h * n01;
    const double gamma = dot(n1, k.v[i]) - h * n11;
    if (!(std::isfinite(beta) && std::isfinite(gamma))) return 0.0;
    const double root = firstPositiveRoot(alpha, beta, gamma);
    if (root < bound) bound = root;
  }
  return bound;
}

// p(t) = c[0] + c[1] t + ... + c[n] t^n and its derivative, by Horner's rule.
double evaluate(const double* c, int n, double t) {
  double v = c[n];
  for (int i = n - 1; i >= 0; --i) v = v * t + c[i];
  return v;
}
void evaluate(const double* c, int n, double t, double& value, double& slope) {
  value = c[n];
  slope = 0.0;
  for (int i = n - 1; i >= 0; --i) {
    slope = slope * t + value;
    value = value * t + c[i];
  }
}

// The root of p in [a, b], a < b, where p is monotone and changes sign: Newton steps while they
// stay inside the bracket, bisection otherwise (Press et al. 2007, Numerical Recipes 3rd ed.,
// §9.4, rtsafe). Returns the bracket's end on a's side, so p has p(a)'s sign on [a, returned].
double refineRoot(const double* c, int n, double a, double b) {
  const bool positiveAtA = evaluate(c, n, a) > 0.0;
  double lo = a, hi = b, t = 0.5 * (a + b);
  for (int i = 0; i < 100 && hi - lo > 1e-15 * largerOf(std::fabs(lo), std::fabs(hi)); ++i) {
    double value = 0.0, slope = 0.0;
    evaluate(c, n, t, value, slope);
    ((value > 0.0) == positiveAtA ? lo : hi) = t;
    const double newton = t - value / slope;
    // Bisect when Newton leaves the bracket, and every fourth step so that a flat p cannot stall.
    t = newton > lo && newton < hi && i % 4 != 3 ? newton : 0.5 * (lo + hi);
  }
  return lo;
}

// The roots of p (degree n <= 3) in the open interval (lo, hi), ascending; returns how many.
// Between consecutive roots of p' (found the same way, down to a linear p') p is monotone, so
// each of its roots is bracketed by a sign change. No division by the leading coefficient: a
// polynomial whose leading terms vanish (a degenerate cubic) needs no special case.
int rootsIn(const double* c, int n, double lo, double hi, double* roots) {
  if (n <= 0 || !(hi > lo)) return 0;
  if (n == 1) {
    if (c[1] == 0.0) return 0;
    const double r = -c[0] / c[1];
    if (!(r > lo && r < hi)) return 0;
    roots[0] = r;
    return 1;
  }
  double d[4], knots[6];
  for (int i = 1; i <= n; ++i) d[i - 1] = c[i] * i;
  int m = 0;
  knots[m++] = lo;
  m += rootsIn(d, n - 1, lo, hi, knots + m);
  knots[m++] = hi;
  int count = 0;
  bool positive = evaluate(c, n, lo) > 0.0;
  for (int i = 1; i < m; ++i) {
    const bool next = evaluate(c, n, knots[i]) > 0.0;
    if (next != positive) roots[count++] = refineRoot(c, n, knots[i - 1], knots[i]);
    positive = next;
  }
  return count;
}

// For p(0) > 0 (degree n <= 4): how far p provably stays positive on [0, end]: up to (just
// before) its first root, infinity if it has none there.
double firstNonPositive(const double* c, int n, double end) {
  double d[4], knots[6];
  for (int i = 1; i <= n; ++i) d[i - 1] = c[i] * i;
  int m = 0;
  knots[m++] = 0.0;
  m += rootsIn(d, n - 1, 0.0, end, knots + m);
  knots[m++] = end;
  for (int i = 1; i < m; ++i) {
    if (!(evaluate(c, n, knots[i]) > 0.0)) return refineRoot(c, n, knots[i - 1], knots[i]);
  }
  return kInfinity;
}

// How far past s the plane through corners 0, 1, 2 keeps farther than h from the origin. That
// plane holds the whole difference set (the triangle; the parallelogram of two edges, whose
// fourth corner r_11 = r_10 + r_01 - r_00 lies in it), so the distance to the set is at least
// the distance to the plane, |f| / |N|, where N(tau) = (r_1 - r_0) x (r_2 - r_0) is quadratic in
// tau and f(tau) = N . r_0 = det(r_0, r_1, r_2) is the cubic whose roots are the coplanarity
// times of Bridson, Fedkiw & Anderson 2002 (§4). With |N|^2 = |N0|^2 + x(tau), |N| <= |N0| +
// x / (2 |N0|) (as sqrt(a^2 + x) <= a + x / (2a)), so the distance exceeds h wherever the quartic
// sign(f(0)) f(tau) - h (|N0| + x(tau) / (2 |N0|)) is positive: up to its first root. All but
// exact for a vertex coming at the face of a turning triangle (with thickness 0, exactly the
// coplanarity time), the case the direction bounds handle worst.
double planeBound(const Corners& k, double s, double h) {
  const Vec3 r0 = k.at(0, s), a = k.at(1, s) - r0, b = k.at(2, s) - r0;
  const Vec3 v0 = k.v[0], ad = k.v[1] - k.v[0], bd = k.v[2] - k.v[0];
  const Vec3 n0 = cross(a, b), n1 = cross(ad, b) + cross(a, bd), n2 = cross(ad, bd);  // N = n0 + n1 t + n2 t^2
  const double len0 = length(n0);
  const double f[4] = {dot(n0, r0), dot(n1, r0) + dot(n0, v0), dot(n2, r0) + dot(n1, v0), dot(n2, v0)};
  if (!(len0 > 0.0) || f[0] == 0.0) return 0.0;
  const double u[5] = {len0, dot(n0, n1) / len0, (dot(n1, n1) + 2.0 * dot(n0, n2)) / (2.0 * len0), dot(n1, n2) / len0,
                       dot(n2, n2) / (2.0 * len0)};
  const double sign = f[0] > 0.0 ? 1.0 : -1.0;
  double p[5], sizeU = 0.0;
  for (int i = 0; i < 5; ++i) {
    p[i] = (i < 4 ? sign * f[i] : 0.0) - h * u[i];
    sizeU += std::fabs(u[i]);
  }
  // The set lies in the computed plane only up to round-off: f is off by about 1e-16 of the size
  // of its terms, sizeF, and h U by as much of its own. Where |N| is small (a degenerate triangle,
  // nearly parallel edges) that is all there is, so the quartic must exceed 1e-13 (sizeF + h
  // sizeU), not 0: then its computed sign is the true one, and a plane that is degenerate, or
  // becomes so during the step, stops the bound instead of fooling it.
  const double sizeF = (length(a) + length(ad)) * (length(b) + length(bd)) * (length(r0) + length(v0));
  p[0] -= 1e-13 * (sizeF + h * sizeU);
  for (const double coefficient : p) {
    if (!std::isfinite(coefficient)) return 0.0;
  }
  if (!(p[0] > 0.0)) return 0.0;
  return firstNonPositive(p, 4, 1.0 - s);
}

// Unit normal of the plane of corners 0, 1, 2 (the triangle, or the parallelogram of two edges),
// on the side of the difference set (n . r_0 > 0); zero if degenerate. Accurate however close
// the set is to the origin: it comes from the corners' differences, not from the closest point.
Vec3 planeDirection(const Corners& k, double s) {
  const Vec3 r0 = k.at(0, s), e1 = k.at(1, s) - r0, e2 = k.at(2, s) - r0;
  const Vec3 n = cross(e1, e2);
  const double nn = dot(n, n);
  if (!(nn > 1e-20 * dot(e1, e1) * dot(e2, e2)) || !std::isfinite(nn)) return {};
  const Vec3 unit = n / std::sqrt(nn);
  return dot(unit, r0) >= 0.0 ? unit : -unit;
}

// Unit direction of the closest vector computed from the feature it lies on. Near contact the
// closest vector c is short and its direction, c / |c|, carries the round-off of its corners
// (about 1e-16 of their size) magnified by size / |c|; the bound then fails to prove any step.
// From the feature instead: a corner is its own closest vector, for an edge of the set c is made
// exactly perpendicular to it, and for the plane the normal comes from the corners' differences.
Vec3 featureDirection(const Corners& k, const Closest& q, double s) {
  if (q.featureSize == 1) {
    const Vec3 r = k.at(q.feature[0], s);
    const double len = length(r);
    return len > 0.0 ? r / len : Vec3{};
  }
  if (q.featureSize == 2) {
    const Vec3 e = k.at(q.feature[1], s) - k.at(q.feature[0], s);
    const double ee = dot(e, e);
    const Vec3 c = ee > 0.0 ? q.c - e * (dot(e, q.c) / ee) : q.c;
    const double len = length(c);
    return len > 0.0 && std::isfinite(len) ? c / len : Vec3{};
  }
  Corners plane = k;  // the feature's three corners as corners 0, 1, 2
  for (int i = 0; i < 3; ++i) {
    plane.r0[i] = k.r0[q.feature[i]];
    plane.v[i] = k.v[q.feature[i]];
  }
  return planeDirection(plane, s);
}

// Unit contact normal when the distance at the contact is too small to give a direction: the
// direction at the previous query (where the pair came from), else the plane of the feature oriented
// against the approach, else against the approach velocity.
Vec3 fallbackNormal(const Corners& k, const Closest& q, double s, const Vec3& previous) {
  if (lengthSquared(previous) > 0.0) return previous;
  const Vec3 approach = frozenRate(k, q);
  const Vec3 plane = planeDirection(k, s);
  if (lengthSquared(plane) > 0.0) return dot(plane, approach) > 0.0 ? -plane : plane;
  const double speed = length(approach);
  if (speed > 0.0 && std::isfinite(speed)) return approach / -speed;
  return {0.0, 0.0, 1.0};
}

// The longest advance past s that one of the bounds proves free of contact (each is valid on
// its own, for any direction it is given), cheapest first, stopping as soon as one reaches past
// s = 1: the direction of the closest vector and, more accurate near contact, that of its
// feature (advanceBound with n1 = 0); the feature turning (the rate of its closest vector); the
// plane of the set, as a direction and as the moving plane (planeBound).
double safeStep(const Corners& k, const Closest& q, double s, double h) {
  const double rest = 1.0 - s;
  double step = advanceBound(k, s, q.c / q.distance, Vec3{}, h);
  if (step > rest) return step;
  const Vec3 feature = featureDirection(k, q, s);
  if (lengthSquared(feature) > 0.0) {
    step = largerOf(step, advanceBound(k, s, feature, Vec3{}, h));  // largerOf drops a NaN
    if (step > rest) return step;
  }
  const Vec3 n0 = lengthSquared(feature) > 0.0 ? feature * q.distance : q.c;
  step = largerOf(step, advanceBound(k, s, n0, closestRate(k, q, s), h));
  if (step > rest) return step;
  const Vec3 plane = planeDirection(k, s);
  if (lengthSquared(plane) > 0.0) {
    step = largerOf(step, advanceBound(k, s, plane, Vec3{}, h));
    if (step > rest) return step;
  }
  return largerOf(step, planeBound(k, s, h));
}

// Whether the set stays farther than h along the direction n (any length) over the whole step:
// n . r / |n| >= the least of the corners' n . r_k(s) / |n|, each linear in s, so its least value
// over [0, 1] is at s = 0 or s = 1 (the bound of advanceBound with tau spanning the step). Squared,
// to spare a square root: most pairs the boxes let through end here. A zero n proves nothing.
bool separatedAlong(const Corners& k, const Vec3& n, double h) {
  const double limit = h * h * dot(n, n);
  const auto beyond = [&](const Vec3& r) {
    const double d = dot(n, r);
    return d > 0.0 && d * d > limit;
  };
  for (int i = 0; i < k.count(); ++i) {
    if (!beyond(k.r0[i]) || !beyond(k.r0[i] + k.v[i])) return false;
  }
  return true;
}

// Two directions that separate most pairs that do not touch: the normal of the set's plane at the
// start (of the triangle; of both edges), toward the first primitive, and the sum of the corners
// over the step (from the second primitive's middle toward the first's).
bool separatedOverStep(const Corners& k, double h) {
  Vec3 plane = cross(k.r0[1] - k.r0[0], k.r0[2] - k.r0[0]);
  if (dot(plane, k.r0[0]) < 0.0) plane = -plane;
  if (separatedAlong(k, plane, h)) return true;
  Vec3 mean;
  for (int i = 0; i < k.count(); ++i) mean += k.r0[i] * 2.0 + k.v[i];
  return separatedAlong(k, mean, h);
}

// Conservative advancement over s in [0, 1] (see the header): returns whether the pair comes
// within h, and then the fraction, the closest points there and the normal.
bool advance(const Corners& k, double h, double& fraction, Closest& hit, Vec3& normal, int& steps) {
  // The largest coordinate of the corners at s = 0 and s = 1: per coordinate and per end, six
  // independent chains of maxsd (one chain of 24 was most of a miss's time). The corners of a
  // step that resolve reaches are finite (resolveStep checks), so std::max needs no NaN rule.
  const auto magnitude = [](const Vec3& r) { return Vec3{std::fabs(r.x), std::fabs(r.y), std::fabs(r.z)}; };
  Vec3 start = magnitude(k.r0[0]), end = magnitude(k.r0[0] + k.v[0]);
  for (int i = 1; i < k.count(); ++i) {
    start = componentMax(start, magnitude(k.r0[i]));
    end = componentMax(end, magnitude(k.r0[i] + k.v[i]));
  }
  const Vec3 both = componentMax(start, end);
  const double scale = std::max({both.x, both.y, both.z});
  const double tol = contactTolerance(h, scale);
  const double hReport = h + tol, hAdvance = h + 0.5 * tol;
  // Most pairs that the boxes let through are clear all step along their plane (a vertex over a
  // face, two edges over each other) or along the line between them: proven without a query.
  steps = 0;
  if (separatedOverStep(k, hAdvance)) return false;
  double s = 0.0;
  Vec3 previous;  // unit closest direction at the previous query; zero before the first
  for (steps = 1;; ++steps) {
    const Closest q = closestAt(k, s);
    bool report = q.distance <= hReport || steps > kMaxAdvanceSteps;
    double next = s;
    if (!report) {
      const double step = safeStep(k, q, s, hAdvance);
      next = s + step;
      // No step proven safe (round-off in the corners beyond tol / 2, possible only for nearly
      // degenerate configurations at near-contact) or too small to move s: report here,
      // conservatively.
      report = !(step > 0.0) || next == s;
      previous = q.c / q.distance;
    }
    if (report) {
      fraction = s;
      hit = q;
      normal = q.distance > 0.1 * tol && q.distance > 0.0 ? q.c / q.distance : fallbackNormal(k, q, s, previous);
      return true;
    }
    if (!(next <= 1.0)) return false;  // the rest of the step is clear
    s = next;
  }
}

}  // namespace

bool vertexTriangleImpact(const Motion& x, const Motion& a, const Motion& b, const Motion& c, double thickness,
                          VertexTriangleContact& contact) {
  assert(thickness >= 0.0);
  Corners k;
  const Motion* tri[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    k.r0[i] = x.start - tri[i]->start;
    k.v[i] = (x.end - tri[i]->end) - k.r0[i];
  }
  double fraction = 0.0;
  Closest hit;
  Vec3 normal;
  int steps = 0;
  const bool found = advance(k, thickness, fraction, hit, normal, steps);
  contact.steps = steps;
  if (!found) return false;
  contact.fraction = fraction;
  for (int i = 0; i < 3; ++i) contact.weight[i] = hit.w[i];
  contact.normal = normal;
  contact.distance = hit.distance;
  return true;
}

bool edgeEdgeImpact(const Motion& p0, const Motion& p1, const Motion& q0, const Motion& q1, double thickness,
                    EdgeEdgeContact& contact) {
  assert(thickness >= 0.0);
  Corners k;
  k.edges = true;
  const Motion* p[2] = {&p0, &p1};
  const Motion* q[2] = {&q0, &q1};
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      k.r0[i + 2 * j] = p[i]->start - q[j]->start;
      k.v[i + 2 * j] = (p[i]->end - q[j]->end) - k.r0[i + 2 * j];
    }
  }
  double fraction = 0.0;
  Closest hit;
  Vec3 normal;
  int steps = 0;
  const bool found = advance(k, thickness, fraction, hit, normal, steps);
  contact.steps = steps;
  if (!found) return false;
  contact.fraction = fraction;
  contact.a = hit.w[0];
  contact.b = hit.w[1];
  contact.normal = normal;
  contact.distance = hit.distance;
  return true;
}

}  // namespace springy

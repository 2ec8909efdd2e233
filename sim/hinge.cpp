#include "sim/hinge.h"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <limits>

#include "sim/lanes.h"

namespace springy {

namespace {

// hingeGeometry and hingeGradient: the same operations, with or without the angle.
template <bool kAngle>
bool geometryOf(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, HingeGeometry& g, double minLeverLeft,
                double minLeverRight) {
  const Vec3 e = x1 - x0;
  const double l01 = length(e);
  if (!(l01 > 0.0)) return false;
  const Vec3 h = e / l01;
  const Vec3 x02 = x2 - x0, x03 = x3 - x0;
  const double d02 = dot(x02, h), d03 = dot(x03, h);
  const Vec3 rl = x02 - h * d02, rr = x03 - h * d03;
  const double lenL = length(rl), lenR = length(rr);
  // A wing vertex (numerically) on the hinge line has no lever arm and no face normal.
  if (!(lenL > 1e-12 * l01) || !(lenR > 1e-12 * l01)) return false;
  // Unit outward normals: h x r / |r| equals the normalised face normal, computed without a
  // second square root.
  const Vec3 nl = cross(h, rl) / lenL;
  const Vec3 nr = cross(rr, h) / lenR;
  if constexpr (kAngle) g.theta = std::atan2(dot(cross(nl, nr), h), dot(nl, nr));
  g.grad[2] = nl * (-1.0 / std::fmax(lenL, minLeverLeft));
  g.grad[3] = nr * (-1.0 / std::fmax(lenR, minLeverRight));
  g.grad[1] = (g.grad[2] * d02 + g.grad[3] * d03) * (-1.0 / l01);
  g.grad[0] = -(g.grad[1] + g.grad[2] + g.grad[3]);
  g.leverLeft = lenL;
  g.leverRight = lenR;
  return true;
}

}  // namespace

bool hingeGeometry(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, HingeGeometry& g,
                   double minLeverLeft, double minLeverRight) {
  return geometryOf<true>(x0, x1, x2, x3, g, minLeverLeft, minLeverRight);
}

bool hingeGradient(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, HingeGeometry& g,
                   double minLeverLeft, double minLeverRight) {
  g.theta = std::numeric_limits<double>::quiet_NaN();
  return geometryOf<false>(x0, x1, x2, x3, g, minLeverLeft, minLeverRight);
}

double dihedralAngle(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  HingeGeometry g;
  return hingeGeometry(x0, x1, x2, x3, g) ? g.theta : 0.0;
}

double angleDifference(double theta, double restAngle) {
  double d = theta - restAngle;
  if (d > kPi) d -= 2 * kPi;
  else if (d <= -kPi) d += 2 * kPi;
  return d;
}

HingeTerms hingeTerms(const Hinge& hinge) {
  HingeTerms t;
  t.restCos = std::cos(hinge.restAngle);
  t.restSin = std::sin(hinge.restAngle);
  for (int i = 0; i < 2; ++i) {
    t.minLeverSquared[i] = hinge.minLever[i] * hinge.minLever[i];
    t.invMinLever[i] = hinge.minLever[i] > 0.0 ? 1.0 / hinge.minLever[i] : std::numeric_limits<double>::infinity();
  }
  return t;
}

namespace {

// atan(t) for |t| <= 1/4 by its Taylor series t - t^3/3 + t^5/5 - ... to t^27: the first term
// left out, t^29/29, is below 2^-53 |t|, so the result is as accurate as std::atan's. The
// polynomial in z = t^2 is evaluated by Estrin's scheme (pairs, then pairs of pairs), which
// has a quarter of Horner's dependency chain. T is double or a vector of doubles (Lanes): the
// same operations in the same order, so every lane gets the scalar result bit for bit.
template <class T>
inline T atanSmall(const T& t) {
  const T z = t * t, z2 = z * z, z4 = z2 * z2, z8 = z4 * z4;
  const T a0 = -1.0 / 3 + z * (1.0 / 5), a1 = -1.0 / 7 + z * (1.0 / 9);
  const T a2 = -1.0 / 11 + z * (1.0 / 13), a3 = -1.0 / 15 + z * (1.0 / 17);
  const T a4 = -1.0 / 19 + z * (1.0 / 21), a5 = -1.0 / 23 + z * (1.0 / 25);
  const T b0 = a0 + z2 * a1, b1 = a2 + z2 * a3, b2 = a4 + z2 * a5;
  const T p = (b0 + z4 * b1) + z8 * (b2 + z4 * (-1.0 / 27));
  return t + t * (z * p);
}

// The hinge of a crushed face fades out (Hinge::minLever, hinge.h): its energy is
// E = 1/2 k delta^2 s_l s_r with s = S(|r| / minLever), S(u) = 3u^2 - 2u^3 below 1 and 1 above (a
// smoothstep: S and S' continuous at 1, and S(u)/u bounded, so the force stays finite as the
// lever arm vanishes). The force is exactly -grad E (conservative: a crushed face can neither
// gain nor pump energy), the damping -d (G . v) G with G = s grad(theta) (never adds energy).
inline void fadeOf(double u, double& s, double& ds) {
  if (u >= 1.0) {
    s = 1.0, ds = 0.0;
  } else {
    s = u * u * (3.0 - 2.0 * u), ds = 6.0 * u * (1.0 - u);
  }
}

// g: the exact gradient of theta; leverL/R: |r_l|, |r_r|.
void fadedForces(const Hinge& hg, const HingeTerms& terms, const std::array<Vec3, 4>& g, const Vec3& e, const Vec3& x02,
                 const Vec3& x03, double ee, double leverL, double leverR, double delta, const Vec3* v, Vec3 out[4]) {
  double sl, dsl, sr, dsr;
  fadeOf(leverL * terms.invMinLever[0], sl, dsl);
  fadeOf(leverR * terms.invMinLever[1], sr, dsr);
  const double fade = sl * sr;
  // Gradients of the lever lengths: r = x0w - e t with t = (x0w . e) / |e|^2 moves with the
  // wing vertex along r^ and with the edge's ends in proportion to (1 - t) and t.
  const double tl = dot(x02, e) / ee, tr = dot(x03, e) / ee;
  const Vec3 ul = (x02 - e * tl) / leverL, ur = (x03 - e * tr) / leverR;
  const double cl = dsl * sr * terms.invMinLever[0], cr = sl * dsr * terms.invMinLever[1];  // ds/d|r_l|, ds/d|r_r|
  const Vec3 ds[4] = {ul * (-(1.0 - tl) * cl) + ur * (-(1.0 - tr) * cr), ul * (-tl * cl) + ur * (-tr * cr), ul * cl,
                      ur * cr};
  Vec3 G[4];
  double rate = 0.0;
  for (int i = 0; i < 4; ++i) {
    G[i] = g[static_cast<std::size_t>(i)] * fade;
    rate += dot(G[i], v[hg.v[i]]);
  }
  const double torque = hg.stiffness * delta + hg.damping * rate;
  const double half = 0.5 * hg.stiffness * delta * delta;
  for (int i = 0; i < 4; ++i) out[i] = G[i] * -torque - ds[i] * half;
}

// The forces of one hinge on its four vertices: the formulas of hingeGeometry rewritten with
// the unnormalised face normals N_l = e x x02 and N_r = x03 x e (e = x1 - x0), for speed:
//   |r_l| = |N_l| / |e|, so g2 = -n_l / |r_l| = -N_l |e| / |N_l|^2 (no square root), and
//   g1 = -((x02 . e) g2 + (x03 . e) g3) / |e|^2;
//   theta - theta0 from its sine and cosine, which only need N_l x N_r and N_l . N_r up to a
//   common positive factor, so atan2 runs only when a hinge is bent over 14 degrees from rest.
// Returns false for the degenerate-geometry guard (the same condition as hingeGeometry's).
inline bool hingeForces(const Hinge& hg, const HingeTerms& terms, const Vec3* x, const Vec3* v, Vec3 out[4]) {
  const Vec3 x0 = x[hg.v[0]];
  const Vec3 e = x[hg.v[1]] - x0, x02 = x[hg.v[2]] - x0, x03 = x[hg.v[3]] - x0;
  const double ee = dot(e, e);
  const Vec3 nl = cross(e, x02), nr = cross(x03, e);
  const double nl2 = dot(nl, nl), nr2 = dot(nr, nr);
  // |r| > 1e-12 |e|  <=>  |N|^2 > 1e-24 |e|^4
  if (!(ee > 0.0) || !(nl2 > 1e-24 * ee * ee) || !(nr2 > 1e-24 * ee * ee)) return false;
  const double l01 = std::sqrt(ee);
  // sin and cos of theta times |N_l| |N_r| |e|, then of theta - theta0 (same factor).
  const double s = dot(cross(nl, nr), e), c = dot(nl, nr) * l01;
  const double sd = s * terms.restCos - c * terms.restSin;
  const double cd = c * terms.restCos + s * terms.restSin;
  const double delta = (cd > 0.0 && std::fabs(sd) <= 0.25 * cd) ? atanSmall(sd / cd) : std::atan2(sd, cd);
  const double wl = l01 / nl2, wr = l01 / nr2;  // g2 = -n_l / |r_l| = -N_l |e| / |N_l|^2
  const Vec3 g2 = nl * -wl;
  const Vec3 g3 = nr * -wr;
  const Vec3 g1 = (g2 * dot(x02, e) + g3 * dot(x03, e)) * (-1.0 / ee);
  const Vec3 g0 = -(g1 + g2 + g3);
  // Crushed face (Hinge::minLever): |r| < minLever  <=>  |N|^2 < minLever^2 |e|^2.
  if (nl2 < terms.minLeverSquared[0] * ee || nr2 < terms.minLeverSquared[1] * ee) {
    fadedForces(hg, terms, {g0, g1, g2, g3}, e, x02, x03, ee, std::sqrt(nl2) / l01, std::sqrt(nr2) / l01, delta, v, out);
    return true;
  }
  const double rate = dot(g0, v[hg.v[0]]) + dot(g1, v[hg.v[1]]) + dot(g2, v[hg.v[2]]) + dot(g3, v[hg.v[3]]);
  const double torque = hg.stiffness * delta + hg.damping * rate;
  out[0] = g0 * -torque;
  out[1] = g1 * -torque;
  out[2] = g2 * -torque;
  out[3] = g3 * -torque;
  return true;
}

// Four hinges at once, one per lane of a vector of four doubles (sim/lanes.h). Each lane
// performs hingeForces' operations in the same order, and the build never fuses a multiply
// and an add (-ffp-contract=off), so a hinge's forces are bit-identical whichever packet, lane,
// instruction set or thread computes them (tests/test_forces.cpp checks against hingeForces).
using lanes::Lanes;

using lanes::gather;
using lanes::sqrt;
using lanes::V3L;

// The forces of hinges hs[0..3] into out[r][corner]; ok[r] is hingeForces' result. Inlined into
// applyHinges' clones (a call per packet to a clone of its own measured slower: the packet's
// forces went through memory to the adding loop, compiled for the baseline target).
__attribute__((always_inline)) inline void hingePacket(const Hinge* const hs[4], const HingeTerms* const ts[4],
                                                       const Vec3* x, const Vec3* v, Vec3 out[4][4], bool ok[4]) {
  using lanes::kLaneOf;
  V3L p[4], w[4];
  for (int i = 0; i < 4; ++i) {
    const uint32_t index[4] = {hs[0]->v[i], hs[1]->v[i], hs[2]->v[i], hs[3]->v[i]};
    p[i] = gather(x, index);
    w[i] = gather(v, index);
  }
  const auto perHinge = [&](auto value) { return Lanes{value(0), value(2), value(1), value(3)}; };  // lane order
  const Lanes restCos = perHinge([&](int r) { return ts[r]->restCos; });
  const Lanes restSin = perHinge([&](int r) { return ts[r]->restSin; });
  const Lanes minLeverSquared[2] = {perHinge([&](int r) { return ts[r]->minLeverSquared[0]; }),
                                    perHinge([&](int r) { return ts[r]->minLeverSquared[1]; })};
  const Lanes stiffness = perHinge([&](int r) { return hs[r]->stiffness; });
  const Lanes damping = perHinge([&](int r) { return hs[r]->damping; });
  const V3L e = p[1] - p[0], x02 = p[2] - p[0], x03 = p[3] - p[0];
  const Lanes ee = dot(e, e);
  const V3L nl = cross(e, x02), nr = cross(x03, e);
  const Lanes nl2 = dot(nl, nl), nr2 = dot(nr, nr);
  const auto valid = (ee > 0.0) & (nl2 > 1e-24 * ee * ee) & (nr2 > 1e-24 * ee * ee);
  const Lanes l01 = sqrt(ee);
  const Lanes s = dot(cross(nl, nr), e), c = dot(nl, nr) * l01;
  const Lanes sd = s * restCos - c * restSin;
  const Lanes cd = c * restCos + s * restSin;
  Lanes delta = atanSmall(sd / cd);
  for (int l = 0; l < 4; ++l) {
    if (!(cd[l] > 0.0 && std::fabs(sd[l]) <= 0.25 * cd[l])) delta[l] = std::atan2(sd[l], cd[l]);
  }
  const Lanes wl = l01 / nl2, wr = l01 / nr2;
  const auto crushed = (nl2 < minLeverSquared[0] * ee) | (nr2 < minLeverSquared[1] * ee);
  const V3L g2 = nl * -wl;
  const V3L g3 = nr * -wr;
  const V3L g1 = (g2 * dot(x02, e) + g3 * dot(x03, e)) * (-1.0 / ee);
  const V3L g0 = -(g1 + g2 + g3);
  const Lanes rate = dot(g0, w[0]) + dot(g1, w[1]) + dot(g2, w[2]) + dot(g3, w[3]);
  const Lanes scale = -(stiffness * delta + damping * rate);
  const V3L g[4] = {g0, g1, g2, g3};
  for (int i = 0; i < 4; ++i) {
    const V3L fi = g[i] * scale;
    lanes::Pair xy[4];
    lanes::untranspose(fi.x, fi.y, xy);
    for (int r = 0; r < 4; ++r) {
      lanes::storePair(&out[r][i].x, xy[r]);
      out[r][i].z = fi.z[kLaneOf[r]];
    }
  }
  for (int r = 0; r < 4; ++r) {
    const int l = kLaneOf[r];
    ok[r] = valid[l] != 0;
    if (ok[r] && crushed[l]) ok[r] = hingeForces(*hs[r], *ts[r], x, v, out[r]);  // rare: fadedForces
  }
}

// Adds the forces of count hinges, the r-th being hinges[indexOf(r)], to the corners whose bit
// is set in maskOf(r): four at a time through hingePacket, the rest one at a time, always
// summed in list order. Always inlined into applyHinges' clones, as applyStrutList (strut.cpp).
template <class IndexOf, class MaskOf>
__attribute__((always_inline)) inline void applyHingeList(const Hinge* hinges, const HingeTerms* terms,
                                                          std::size_t count, IndexOf indexOf, MaskOf maskOf,
                                                          const Vec3* x, const Vec3* v, Vec3* f) {
  Vec3 out[4][4];
  bool ok[4];
  const auto add = [&](std::size_t r, const Vec3 forces[4]) {
    const Hinge& hg = hinges[indexOf(r)];
    const uint32_t mask = maskOf(r);
    for (int i = 0; i < 4; ++i) {
      if (mask & (1u << i)) f[hg.v[i]] += forces[i];
    }
  };
  std::size_t r = 0;
  for (; r + 4 <= count; r += 4) {
    const Hinge* hs[4];
    const HingeTerms* ts[4];
    for (std::size_t l = 0; l < 4; ++l) hs[l] = &hinges[indexOf(r + l)], ts[l] = &terms[indexOf(r + l)];
    hingePacket(hs, ts, x, v, out, ok);
    for (std::size_t l = 0; l < 4; ++l) {
      if (ok[l]) add(r + l, out[l]);
    }
  }
  for (; r < count; ++r) {
    if (hingeForces(hinges[indexOf(r)], terms[indexOf(r)], x, v, out[0])) add(r, out[0]);
  }
}

}  // namespace

// Both loops (range and list) spelt out, as applyStruts (strut.cpp) does and for its reason.
__attribute__((target_clones("avx2", "default"))) void applyHinges(const Hinge* hinges, const HingeTerms* terms,
                                                                   Elements elements, const Vec3* x, const Vec3* v,
                                                                   Vec3* f) {
  if (const ElementRef* list = elements.list()) {
    applyHingeList(hinges, terms, elements.count(), Elements::ListIndex{list}, Elements::ListMask{list}, x, v, f);
  } else {
    applyHingeList(hinges, terms, elements.count(), Elements::RangeIndex{elements.first()}, Elements::AllVertices{}, x,
                   v, f);
  }
}

double hingeEnergy(const Hinge* hinges, std::size_t begin, std::size_t end, const Vec3* x) {
  double e = 0.0;
  for (std::size_t k = begin; k < end; ++k) {
    const Hinge& hg = hinges[k];
    HingeGeometry g;
    if (!hingeGeometry(x[hg.v[0]], x[hg.v[1]], x[hg.v[2]], x[hg.v[3]], g)) continue;  // the force skips it too
    const double d = angleDifference(g.theta, hg.restAngle);
    double sl = 1.0, sr = 1.0, unused;
    if (hg.minLever[0] > 0.0) fadeOf(g.leverLeft / hg.minLever[0], sl, unused);
    if (hg.minLever[1] > 0.0) fadeOf(g.leverRight / hg.minLever[1], sr, unused);
    e += 0.5 * hg.stiffness * d * d * (sl * sr);
  }
  return e;
}

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

Vector3d ev(const Vec3& a) { return {a.x, a.y, a.z}; }

Matrix3d skew(const Vector3d& a) {
  Matrix3d s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;  // s b = a x b
}

// Derivatives of G(h, a) = -(h x a) / s, s = |a|^2 - (a.h)^2, with respect to a and h.
void wingDerivatives(const Vector3d& h, const Vector3d& a, Matrix3d& dGda, Matrix3d& dGdh) {
  const Vector3d q = h.cross(a);
  const double ah = a.dot(h);
  const double s = a.squaredNorm() - ah * ah;
  const Vector3d r = a - ah * h;
  dGda = -skew(h) / s + (2.0 / (s * s)) * q * r.transpose();
  dGdh = -skew(a) * (-1.0 / s) - (2.0 * ah / (s * s)) * q * a.transpose();
}

}  // namespace

bool dihedralHessian(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, Matrix12& H) {
  HingeGeometry geo;
  if (!hingeGeometry(x0, x1, x2, x3, geo)) return false;
  const Vector3d e = ev(x1 - x0);
  const double l = e.norm();
  const Vector3d h = e / l;
  const Matrix3d Pl = (Matrix3d::Identity() - h * h.transpose()) / l;  // d h / d x1
  const Vector3d a = ev(x2 - x0), b = ev(x3 - x0);
  Matrix3d Gaa, Gha, Gab, Ghb;
  wingDerivatives(h, a, Gaa, Gha);
  wingDerivatives(h, b, Gab, Ghb);
  const Matrix3d Jea = Gha * Pl, Jeb = Ghb * Pl;  // through the edge direction
  H.setZero();
  auto blk = [&](int i, int j) { return H.block<3, 3>(3 * i, 3 * j); };
  // g2 = G(h, a)
  blk(2, 2) = Gaa;
  blk(2, 1) = Jea;
  blk(2, 0) = -Gaa - Jea;
  // g3 = -G(h, b)
  blk(3, 3) = -Gab;
  blk(3, 1) = -Jeb;
  blk(3, 0) = Gab + Jeb;
  // g1 = -(d02 g2 + d03 g3) / l
  const Vector3d g1 = ev(geo.grad[1]), g2 = ev(geo.grad[2]), g3 = ev(geo.grad[3]);
  const double d02 = a.dot(h), d03 = b.dot(h);
  // Row gradients of d02, d03 and l with respect to x0..x3.
  Eigen::Matrix<double, 1, 3> dd02[4], dd03[4], dl[4];
  const Eigen::Matrix<double, 1, 3> ht = h.transpose(), zero = Eigen::Matrix<double, 1, 3>::Zero();
  dd02[2] = ht;
  dd02[3] = zero;
  dd02[1] = a.transpose() * Pl;
  dd02[0] = -ht - dd02[1];
  dd03[2] = zero;
  dd03[3] = ht;
  dd03[1] = b.transpose() * Pl;
  dd03[0] = -ht - dd03[1];
  dl[0] = -ht;
  dl[1] = ht;
  dl[2] = dl[3] = zero;
  for (int k = 0; k < 4; ++k) {
    const Matrix3d dg2 = blk(2, k), dg3 = blk(3, k);
    blk(1, k) = -(g2 * dd02[k] + d02 * dg2 + g3 * dd03[k] + d03 * dg3) / l - (g1 / l) * dl[k];
  }
  // g0 = -(g1 + g2 + g3)
  for (int k = 0; k < 4; ++k) blk(0, k) = -(Matrix3d(blk(1, k)) + Matrix3d(blk(2, k)) + Matrix3d(blk(3, k)));
  return true;
}

bool hingeJacobian(const Hinge& hg, const Vec3* x, const Vec3* v, Matrix12& dfdx, Matrix12& dfdv, bool definite) {
  const Vec3 &x0 = x[hg.v[0]], &x1 = x[hg.v[1]], &x2 = x[hg.v[2]], &x3 = x[hg.v[3]];
  HingeGeometry geo;
  // The solver's (definite) Jacobian bounds the lever the gradient divides by, so it stays
  // finite in a crushed face; there it only approximates the faded force's derivative (hinge.h),
  // which costs Newton iterations, not accuracy: the residual uses the force itself. The exact
  // Jacobian uses the exact gradient.
  if (!hingeGeometry(x0, x1, x2, x3, geo, definite ? hg.minLever[0] : 0.0, definite ? hg.minLever[1] : 0.0)) {
    return false;
  }
  Eigen::Matrix<double, 12, 1> g, vel;
  for (int i = 0; i < 4; ++i) {
    g.segment<3>(3 * i) = ev(geo.grad[i]);
    vel.segment<3>(3 * i) = ev(v[hg.v[i]]);
  }
  dfdv = -hg.damping * g * g.transpose();
  if (definite) {
    dfdx = -hg.stiffness * g * g.transpose();
    return true;
  }
  Matrix12 H;
  if (!dihedralHessian(x0, x1, x2, x3, H)) return false;
  const double rate = g.dot(vel);
  const double torque = hg.stiffness * angleDifference(geo.theta, hg.restAngle) + hg.damping * rate;
  // d torque / d x_k = k g_k^T + d sum_j v_j^T H_jk
  const Eigen::Matrix<double, 1, 12> dtorque = hg.stiffness * g.transpose() + hg.damping * (vel.transpose() * H);
  dfdx = -g * dtorque - torque * H;
  return true;
}

std::size_t hingeCount(const Model& model) { return model.hinges.size(); }

void hingeVertices(const Model& model, std::size_t hinge, uint32_t* vertices) {
  for (int a = 0; a < 4; ++a) vertices[a] = model.hinges[hinge].v[a];
}

bool hingeBlocks(const Model& model, std::size_t hinge, const Vec3* x, const Vec3* v, bool definite, Matrix12& dfdx,
                 Matrix12& dfdv) {
  return hingeJacobian(model.hinges[hinge], x, v, dfdx, dfdv, definite);
}

void hingeVbdTerm(const VbdCall& call, std::size_t hinge, int slot, Vec3& f, Sym3& H) {
  const Hinge& hg = call.model.hinges[hinge];
  const Vec3* x = call.x;
  HingeGeometry g;
  if (!hingeGeometry(x[hg.v[0]], x[hg.v[1]], x[hg.v[2]], x[hg.v[3]], g, hg.minLever[0], hg.minLever[1])) return;
  double rate = 0.0;
  for (int b = 0; b < 4; ++b) rate += dot(g.grad[b], x[hg.v[b]] - call.x0[hg.v[b]]);
  rate *= call.invH;
  f -= g.grad[slot] * (hg.stiffness * angleDifference(g.theta, hg.restAngle) + hg.damping * rate);
  H.addOuter(g.grad[slot], hg.stiffness + hg.damping * call.invH);
}

void hingeBoundRows(const Model& model, const Vec3* x, const double* invMass, uint32_t body, RowBound* rows) {
  const BodyInfo& info = model.bodies[body];
  HingeGeometry g;
  for (uint32_t h = info.firstHinge; h < info.firstHinge + info.hingeCount; ++h) {
    const Hinge& hg = model.hinges[h];
    if (!hingeGradient(x[hg.v[0]], x[hg.v[1]], x[hg.v[2]], x[hg.v[3]], g, hg.minLever[0], hg.minLever[1])) continue;
    double w[4];  // |g_i| / sqrt(m_i), 0 for pinned vertices
    for (int a = 0; a < 4; ++a) w[a] = std::sqrt(lengthSquared(g.grad[a]) * invMass[hg.v[a]]);
    const double sum = w[0] + w[1] + w[2] + w[3];
    for (int a = 0; a < 4; ++a) {
      if (w[a] == 0.0) continue;  // pinned
      RowBound& row = rows[hg.v[a] - info.firstVertex];
      row.hingeStiffness += hg.stiffness * w[a] * sum;
      row.hingeDamping += hg.damping * w[a] * sum;
    }
  }
}

}  // namespace springy

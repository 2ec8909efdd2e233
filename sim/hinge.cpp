#include "sim/hinge.h"

#include <cmath>
#include <limits>

namespace springy {

bool hingeGeometry(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, HingeGeometry& g, double minLeverLeft,
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
  g.theta = std::atan2(dot(cross(nl, nr), h), dot(nl, nr));
  g.grad[2] = nl * (-1.0 / std::fmax(lenL, minLeverLeft));
  g.grad[3] = nr * (-1.0 / std::fmax(lenR, minLeverRight));
  g.grad[1] = (g.grad[2] * d02 + g.grad[3] * d03) * (-1.0 / l01);
  g.grad[0] = -(g.grad[1] + g.grad[2] + g.grad[3]);
  g.leverLeft = lenL;
  g.leverRight = lenR;
  return true;
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
// has a quarter of Horner's dependency chain.
inline double atanSmall(double t) {
  const double z = t * t, z2 = z * z, z4 = z2 * z2, z8 = z4 * z4;
  const double a0 = -1.0 / 3 + z * (1.0 / 5), a1 = -1.0 / 7 + z * (1.0 / 9);
  const double a2 = -1.0 / 11 + z * (1.0 / 13), a3 = -1.0 / 15 + z * (1.0 / 17);
  const double a4 = -1.0 / 19 + z * (1.0 / 21), a5 = -1.0 / 23 + z * (1.0 / 25);
  const double b0 = a0 + z2 * a1, b1 = a2 + z2 * a3, b2 = a4 + z2 * a5;
  const double p = (b0 + z4 * b1) + z8 * (b2 + z4 * (-1.0 / 27));
  return t + t * (z * p);
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
  // Lever-arm guard (Hinge::minLever): |r| < minLever  <=>  |N|^2 < minLever^2 |e|^2.
  const double wl = nl2 < terms.minLeverSquared[0] * ee ? terms.invMinLever[0] / std::sqrt(nl2) : l01 / nl2;
  const double wr = nr2 < terms.minLeverSquared[1] * ee ? terms.invMinLever[1] / std::sqrt(nr2) : l01 / nr2;
  const Vec3 g2 = nl * -wl;
  const Vec3 g3 = nr * -wr;
  const Vec3 g1 = (g2 * dot(x02, e) + g3 * dot(x03, e)) * (-1.0 / ee);
  const Vec3 g0 = -(g1 + g2 + g3);
  const double rate = dot(g0, v[hg.v[0]]) + dot(g1, v[hg.v[1]]) + dot(g2, v[hg.v[2]]) + dot(g3, v[hg.v[3]]);
  const double torque = hg.stiffness * delta + hg.damping * rate;
  out[0] = g0 * -torque;
  out[1] = g1 * -torque;
  out[2] = g2 * -torque;
  out[3] = g3 * -torque;
  return true;
}

}  // namespace

void applyHinges(const Hinge* hinges, const HingeTerms* terms, std::size_t begin, std::size_t end, const Vec3* x,
                 const Vec3* v, Vec3* f) {
  Vec3 out[4];
  for (std::size_t k = begin; k < end; ++k) {
    const Hinge& hg = hinges[k];
    if (!hingeForces(hg, terms[k], x, v, out)) continue;
    for (int i = 0; i < 4; ++i) f[hg.v[i]] += out[i];
  }
}

void applyHingesOwned(const Hinge* hinges, const HingeTerms* terms, const ElementRef* list, std::size_t count,
                 const Vec3* x, const Vec3* v, Vec3* f) {
  Vec3 out[4];
  for (std::size_t r = 0; r < count; ++r) {
    const Hinge& hg = hinges[list[r].index];
    if (!hingeForces(hg, terms[list[r].index], x, v, out)) continue;
    for (int i = 0; i < 4; ++i) {
      if (list[r].mask & (1u << i)) f[hg.v[i]] += out[i];
    }
  }
}

void applyHinges(const Hinge* hinges, std::size_t begin, std::size_t end, const Vec3* x, const Vec3* v, Vec3* f) {
  for (std::size_t k = begin; k < end; ++k) {
    const HingeTerms terms = hingeTerms(hinges[k]);
    applyHinges(hinges + k, &terms, std::size_t{0}, std::size_t{1}, x, v, f);
  }
}

double hingeEnergy(const Hinge* hinges, std::size_t begin, std::size_t end, const Vec3* x) {
  double e = 0.0;
  for (std::size_t k = begin; k < end; ++k) {
    const Hinge& hg = hinges[k];
    const double d = angleDifference(dihedralAngle(x[hg.v[0]], x[hg.v[1]], x[hg.v[2]], x[hg.v[3]]), hg.restAngle);
    e += 0.5 * hg.stiffness * d * d;
  }
  return e;
}

}  // namespace springy

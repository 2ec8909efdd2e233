#include "sim/hinge.h"

#include <cmath>

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

void applyHinges(const Hinge* hinges, std::size_t begin, std::size_t end, const Vec3* x, const Vec3* v, Vec3* f) {
  HingeGeometry g;
  for (std::size_t k = begin; k < end; ++k) {
    const Hinge& hg = hinges[k];
    if (!hingeGeometry(x[hg.v[0]], x[hg.v[1]], x[hg.v[2]], x[hg.v[3]], g, hg.minLever[0], hg.minLever[1])) continue;
    double rate = 0.0;  // d theta / dt
    for (int i = 0; i < 4; ++i) rate += dot(g.grad[i], v[hg.v[i]]);
    const double torque = hg.stiffness * angleDifference(g.theta, hg.restAngle) + hg.damping * rate;
    for (int i = 0; i < 4; ++i) f[hg.v[i]] -= g.grad[i] * torque;
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

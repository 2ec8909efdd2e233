// springy: prescribed rigid motion, for things that move on their own (kinematic colliders,
// pinned vertices that follow a track).
//
// A motion moves a point p of the thing at rest to
//   x(t) = R(t) (p - c) + c + d(t)
// with c the centre of rotation, R(t) the rotation by the angle theta(t) = omega t about a fixed
// unit axis (Rodrigues' formula), and d(t) the translation: keyframes (t_k, d_k), held before the
// first and after the last, linear between them or a cubic Hermite spline (Catmull-Rom tangents
// inside, made monotone so that it never overshoots a key, e.g. flat where two keys are equal;
// zero at the ends: it starts and stops smoothly; C1 everywhere), plus an oscillation
// A sin(2 pi f t + phi). A point moving with the thing has the velocity
//   v = d'(t) + w x (x - c - d(t)),  w = omega axis.
// Everything is a closed form of t: the same time gives the same bits on any thread count.
#pragma once

#include <vector>

#include "sim/vec3.h"

namespace springy {

// A rigid placement: x = R (p - c) + c + d, with R stored as its three columns.
struct Pose {
  Vec3 rx{1, 0, 0}, ry{0, 1, 0}, rz{0, 0, 1};
  Vec3 centre, shift;  // c, d
  Vec3 rotate(const Vec3& v) const { return rx * v.x + ry * v.y + rz * v.z; }
  Vec3 unrotate(const Vec3& v) const { return {dot(rx, v), dot(ry, v), dot(rz, v)}; }
  Vec3 apply(const Vec3& p) const { return rotate(p - centre) + centre + shift; }
  Vec3 inverse(const Vec3& x) const { return unrotate(x - centre - shift) + centre; }
};

struct Movement {
  struct Key {
    double time;
    Vec3 offset;
  };
  std::vector<Key> keys;  // translation keyframes, by time (strictly increasing)
  bool cubic = false;     // interpolation: false linear, true cubic Hermite
  Vec3 amplitude;         // oscillation [m]
  double frequency = 0.0; // [Hz]
  double phase = 0.0;     // [rad]
  Vec3 axis{0, 1, 0};     // rotation axis (unit)
  Vec3 centre;            // centre of rotation [m]
  double spin = 0.0;      // angular speed about the axis [rad/s]

  // Whether it moves at all (a motion with no keys, no oscillation and no spin is the identity).
  bool moves() const;
  Pose pose(double t) const;
  Vec3 translation(double t) const;          // d(t)
  Vec3 translationVelocity(double t) const;  // d'(t)
  // The velocity at time t of the point of the moving thing that is at x then.
  Vec3 velocityAt(const Vec3& x, double t) const;
  // The keyframes' times: where the motion's velocity may jump (linear keys) or its
  // acceleration (cubic ones); an adaptive step lands on them.
  std::vector<double> kinks() const;
};

}  // namespace springy

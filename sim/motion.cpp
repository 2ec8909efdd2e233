#include "sim/motion.h"

#include <algorithm>
#include <cmath>

namespace springy {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// The segment of `keys` that holds t (keys[k].time <= t < keys[k + 1].time), for 2 keys or more.
std::size_t segmentOf(const std::vector<Movement::Key>& keys, double t) {
  const auto after = std::upper_bound(keys.begin(), keys.end(), t,
                                      [](double time, const Movement::Key& k) { return time < k.time; });
  const std::size_t k = static_cast<std::size_t>(after - keys.begin());
  return std::min(std::max<std::size_t>(k, 1), keys.size() - 1) - 1;
}

// The tangent at key k, per coordinate: Catmull-Rom's (the chord from its neighbours), made
// monotone as Fritsch & Carlson (1980, SIAM J. Numer. Anal. 17(2)) show: zero where the path
// turns or holds (the slopes on the two sides differ in sign or one is zero), and at most three
// times the smaller slope, so that no segment overshoots its keys (a press held down between
// two equal keys stays there). Zero at the ends.
Vec3 tangentAt(const std::vector<Movement::Key>& keys, std::size_t k) {
  if (k == 0 || k + 1 >= keys.size()) return {};
  const Vec3 chord = (keys[k + 1].offset - keys[k - 1].offset) / (keys[k + 1].time - keys[k - 1].time);
  const Vec3 before = (keys[k].offset - keys[k - 1].offset) / (keys[k].time - keys[k - 1].time);
  const Vec3 after = (keys[k + 1].offset - keys[k].offset) / (keys[k + 1].time - keys[k].time);
  Vec3 m;
  for (int c = 0; c < 3; ++c) {
    if (!(before[c] * after[c] > 0.0)) continue;  // a turn or a hold: flat here
    const double limit = 3.0 * std::min(std::fabs(before[c]), std::fabs(after[c]));
    m[c] = std::copysign(std::min(std::fabs(chord[c]), limit), chord[c]);
  }
  return m;
}

}  // namespace

bool Movement::moves() const {
  return keys.size() >= 2 || (frequency > 0.0 && length(amplitude) > 0.0) || spin != 0.0;
}

Vec3 Movement::translation(double t) const {
  Vec3 d;
  if (keys.size() == 1 || (!keys.empty() && t <= keys.front().time)) {
    d = keys.front().offset;
  } else if (!keys.empty() && t >= keys.back().time) {
    d = keys.back().offset;
  } else if (keys.size() >= 2) {
    const std::size_t k = segmentOf(keys, t);
    const Key &a = keys[k], &b = keys[k + 1];
    const double h = b.time - a.time, s = (t - a.time) / h;
    if (!cubic) {
      d = a.offset + (b.offset - a.offset) * s;
    } else {
      const double s2 = s * s, s3 = s2 * s;
      d = a.offset * (2 * s3 - 3 * s2 + 1) + tangentAt(keys, k) * (h * (s3 - 2 * s2 + s)) +
          b.offset * (-2 * s3 + 3 * s2) + tangentAt(keys, k + 1) * (h * (s3 - s2));
    }
  }
  if (frequency > 0.0) d += amplitude * std::sin(kTwoPi * frequency * t + phase);
  return d;
}

Vec3 Movement::translationVelocity(double t) const {
  Vec3 v;
  if (keys.size() >= 2 && t >= keys.front().time && t < keys.back().time) {
    const std::size_t k = segmentOf(keys, t);
    const Key &a = keys[k], &b = keys[k + 1];
    const double h = b.time - a.time, s = (t - a.time) / h;
    if (!cubic) {
      v = (b.offset - a.offset) / h;
    } else {
      const double s2 = s * s;
      v = (a.offset * (6 * s2 - 6 * s) + b.offset * (-6 * s2 + 6 * s)) / h + tangentAt(keys, k) * (3 * s2 - 4 * s + 1) +
          tangentAt(keys, k + 1) * (3 * s2 - 2 * s);
    }
  }
  if (frequency > 0.0) v += amplitude * (kTwoPi * frequency * std::cos(kTwoPi * frequency * t + phase));
  return v;
}

Pose Movement::pose(double t) const {
  Pose p;
  p.centre = centre;
  p.shift = translation(t);
  if (spin != 0.0) {
    // Rodrigues: R v = v cos a + (k x v) sin a + k (k . v)(1 - cos a).
    const double a = spin * t, c = std::cos(a), s = std::sin(a);
    const Vec3& k = axis;
    const auto column = [&](const Vec3& e) { return e * c + cross(k, e) * s + k * (dot(k, e) * (1.0 - c)); };
    p.rx = column({1, 0, 0});
    p.ry = column({0, 1, 0});
    p.rz = column({0, 0, 1});
  }
  return p;
}

Vec3 Movement::velocityAt(const Vec3& x, double t) const {
  Vec3 v = translationVelocity(t);
  if (spin != 0.0) v += cross(axis * spin, x - centre - translation(t));
  return v;
}

std::vector<double> Movement::kinks() const {
  std::vector<double> times;
  if (keys.size() >= 2) {
    for (const Key& k : keys) times.push_back(k.time);
  }
  return times;
}

}  // namespace springy

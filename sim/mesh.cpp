#include "sim/mesh.h"

#include <limits>

namespace springy {

double signedVolume(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles) {
  // Sum of signed tetrahedra (origin, a, b, c): divergence theorem, exact for a closed mesh.
  double sixVolume = 0.0;
  for (const Triangle& t : triangles) {
    sixVolume += dot(positions[t[0]], cross(positions[t[1]], positions[t[2]]));
  }
  return sixVolume / 6.0;
}

Bounds boundsOf(const std::vector<Vec3>& positions) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  Bounds b{{inf, inf, inf}, {-inf, -inf, -inf}};
  for (const Vec3& p : positions) {
    b.lo = componentMin(b.lo, p);
    b.hi = componentMax(b.hi, p);
  }
  return b;
}

}  // namespace springy

#include "sim/strut.h"

#include <cmath>

namespace springy {

void applyStruts(const Strut* struts, std::size_t begin, std::size_t end, const Vec3* x, const Vec3* v, Vec3* f) {
  for (std::size_t s = begin; s < end; ++s) {
    const Strut& st = struts[s];
    const Vec3 xij = x[st.j] - x[st.i];
    const double l = length(xij);
    // Guard: two coincident ends have no direction; the strut exerts nothing this instant.
    // (Rest lengths are validated at load, so this only happens mid-collapse.)
    if (!(l > 0.0)) continue;
    const Vec3 u = xij / l;
    const double magnitude = st.stiffness * (l - st.restLength) + st.damping * dot(v[st.j] - v[st.i], u);
    const Vec3 fi = u * magnitude;
    f[st.i] += fi;
    f[st.j] -= fi;
  }
}

double strutEnergy(const Strut* struts, std::size_t begin, std::size_t end, const Vec3* x) {
  double e = 0.0;
  for (std::size_t s = begin; s < end; ++s) {
    const Strut& st = struts[s];
    const double stretch = length(x[st.j] - x[st.i]) - st.restLength;
    e += 0.5 * st.stiffness * stretch * stretch;
  }
  return e;
}

}  // namespace springy

#include "sim/strut.h"

#include <algorithm>
#include <cmath>

namespace springy {

namespace {

// The force on end i (end j gets its negative). Returns false for coincident ends: they have
// no direction, and the strut exerts nothing this instant. (Rest lengths are validated at
// load, so this only happens mid-collapse.)
inline bool strutForce(const Strut& st, const Vec3* x, const Vec3* v, Vec3& fi) {
  const Vec3 xij = x[st.j] - x[st.i];
  const double l = length(xij);
  if (!(l > 0.0)) return false;
  const Vec3 u = xij * (1.0 / l);
  fi = u * (st.stiffness * (l - st.restLength) + st.damping * dot(v[st.j] - v[st.i], u));
  return true;
}

}  // namespace

void applyStruts(const Strut* struts, std::size_t begin, std::size_t end, const Vec3* x, const Vec3* v, Vec3* f) {
  Vec3 fi;
  for (std::size_t s = begin; s < end; ++s) {
    const Strut& st = struts[s];
    if (!strutForce(st, x, v, fi)) continue;
    f[st.i] += fi;
    f[st.j] -= fi;
  }
}

void applyStrutsOwned(const Strut* struts, const ElementRef* list, std::size_t count, const Vec3* x, const Vec3* v,
                 Vec3* f) {
  Vec3 fi;
  for (std::size_t r = 0; r < count; ++r) {
    const Strut& st = struts[list[r].index];
    if (!strutForce(st, x, v, fi)) continue;
    if (list[r].mask & 1u) f[st.i] += fi;
    if (list[r].mask & 2u) f[st.j] -= fi;
  }
}

StrutMeasures measureStruts(const Strut* struts, std::size_t begin, std::size_t end, const Vec3* x) {
  StrutMeasures m;
  for (std::size_t s = begin; s < end; ++s) {
    const Strut& st = struts[s];
    const double stretch = length(x[st.j] - x[st.i]) - st.restLength;
    m.energy += 0.5 * st.stiffness * stretch * stretch;
    m.maxStrain = std::max(m.maxStrain, std::fabs(stretch) / st.restLength);
  }
  return m;
}

}  // namespace springy

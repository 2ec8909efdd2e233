#include "sim/strut.h"

#include <algorithm>
#include <cmath>

// strutPacket returns 32-byte vectors through inlined helpers local to this file; GCC's note
// that such calls have another ABI with and without AVX concerns no caller.
#pragma GCC diagnostic ignored "-Wpsabi"

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

// Four struts at once, one per lane of a vector of four doubles (GCC's vector extension, as
// the hinge packet in hinge.cpp): strutForce's operations in the same order, never fused
// (-ffp-contract=off), so each strut's force is bit-identical to strutForce's. The gain is
// the square root and the division, which the scalar kernel waits on one strut at a time.
typedef double Lanes __attribute__((vector_size(32)));

inline void strutPacket(const Strut* const s[4], const Vec3* x, const Vec3* v, Vec3 fi[4], bool ok[4]) {
  Lanes dx, dy, dz, wx, wy, wz, k, d, l0;
  for (int l = 0; l < 4; ++l) {
    const Strut& st = *s[l];
    const Vec3 xij = x[st.j] - x[st.i], vij = v[st.j] - v[st.i];
    dx[l] = xij.x, dy[l] = xij.y, dz[l] = xij.z;
    wx[l] = vij.x, wy[l] = vij.y, wz[l] = vij.z;
    k[l] = st.stiffness, d[l] = st.damping, l0[l] = st.restLength;
  }
  const Lanes ll = dx * dx + dy * dy + dz * dz;
  Lanes len;
  for (int l = 0; l < 4; ++l) len[l] = std::sqrt(ll[l]);  // one vsqrtpd with AVX
  const Lanes inv = 1.0 / len;
  const Lanes ux = dx * inv, uy = dy * inv, uz = dz * inv;
  const Lanes scale = k * (len - l0) + d * (wx * ux + wy * uy + wz * uz);
  const Lanes fx = ux * scale, fy = uy * scale, fz = uz * scale;
  for (int l = 0; l < 4; ++l) {
    ok[l] = len[l] > 0.0;
    fi[l] = Vec3{fx[l], fy[l], fz[l]};
  }
}

// Adds the forces of count struts, the r-th being struts[indexOf(r)], to the ends whose bit is
// set in maskOf(r) (bit 0: i, bit 1: j): four at a time, the rest one at a time, always summed
// in list order.
template <class IndexOf, class MaskOf>
inline void applyStrutList(const Strut* struts, std::size_t count, IndexOf indexOf, MaskOf maskOf, const Vec3* x,
                           const Vec3* v, Vec3* f) {
  const auto add = [&](std::size_t r, const Vec3& fi) {
    const Strut& st = struts[indexOf(r)];
    const uint32_t mask = maskOf(r);
    if (mask & 1u) f[st.i] += fi;
    if (mask & 2u) f[st.j] -= fi;
  };
  Vec3 fi[4];
  bool ok[4];
  std::size_t r = 0;
  for (; r + 4 <= count; r += 4) {
    const Strut* s[4] = {&struts[indexOf(r)], &struts[indexOf(r + 1)], &struts[indexOf(r + 2)],
                         &struts[indexOf(r + 3)]};
    strutPacket(s, x, v, fi, ok);
    for (std::size_t l = 0; l < 4; ++l) {
      if (ok[l]) add(r + l, fi[l]);
    }
  }
  for (; r < count; ++r) {
    if (strutForce(struts[indexOf(r)], x, v, fi[0])) add(r, fi[0]);
  }
}

}  // namespace

__attribute__((target_clones("avx2", "default"))) void applyStruts(const Strut* struts, std::size_t begin,
                                                                   std::size_t end, const Vec3* x, const Vec3* v,
                                                                   Vec3* f) {
  applyStrutList(
      struts, end - begin, [begin](std::size_t r) { return begin + r; }, [](std::size_t) { return 3u; }, x, v, f);
}

__attribute__((target_clones("avx2", "default"))) void applyStrutsOwned(const Strut* struts, const ElementRef* list,
                                                                        std::size_t count, const Vec3* x,
                                                                        const Vec3* v, Vec3* f) {
  applyStrutList(
      struts, count, [list](std::size_t r) { return list[r].index; }, [list](std::size_t r) { return list[r].mask; },
      x, v, f);
}

namespace {

inline void measureStrut(const Strut& st, const Vec3* x, double& energy, double& maxStrain) {
  const double stretch = length(x[st.j] - x[st.i]) - st.restLength;
  energy += 0.5 * st.stiffness * stretch * stretch;
  maxStrain = std::max(maxStrain, std::fabs(stretch) / st.restLength);
}

}  // namespace

// Four struts at a time in vector lanes, each lane summing its own energies (the square roots
// and divisions, as in the force kernel, are what one strut at a time waits on); the lanes'
// sums are added in lane order at the end, so the result depends only on [begin, end).
__attribute__((target_clones("avx2", "default"))) StrutMeasures measureStruts(const Strut* struts, std::size_t begin,
                                                                              std::size_t end, const Vec3* x) {
  Lanes energy = {0.0, 0.0, 0.0, 0.0}, strain = {0.0, 0.0, 0.0, 0.0};
  std::size_t s = begin;
  for (; s + 4 <= end; s += 4) {
    Lanes dx, dy, dz, k, l0;
    for (int l = 0; l < 4; ++l) {
      const Strut& st = struts[s + static_cast<std::size_t>(l)];
      const Vec3 xij = x[st.j] - x[st.i];
      dx[l] = xij.x, dy[l] = xij.y, dz[l] = xij.z;
      k[l] = st.stiffness, l0[l] = st.restLength;
    }
    const Lanes ll = dx * dx + dy * dy + dz * dz;
    Lanes stretch;
    for (int l = 0; l < 4; ++l) stretch[l] = std::sqrt(ll[l]);
    stretch = stretch - l0;
    energy += 0.5 * k * stretch * stretch;
    const Lanes magnitude = stretch < 0.0 ? -stretch : stretch;
    const Lanes ratio = magnitude / l0;
    strain = strain < ratio ? ratio : strain;  // std::max's order: a NaN ratio leaves strain
  }
  StrutMeasures m;
  m.energy = ((energy[0] + energy[1]) + energy[2]) + energy[3];
  m.maxStrain = std::max({strain[0], strain[1], strain[2], strain[3]});
  for (; s < end; ++s) measureStrut(struts[s], x, m.energy, m.maxStrain);
  return m;
}

}  // namespace springy

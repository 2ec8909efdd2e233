#include "sim/strut.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "sim/lanes.h"

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
// the square root and the division, which the scalar kernel waits on one strut at a time, and
// fewer loads: a vertex's x and y move as one 16-byte pair, and so do a strut's rest length
// and stiffness (a strut reads 16 values and writes 6; one load at a time it was 23 and 6).
using lanes::Lanes;
using lanes::loadPair;
using lanes::Pair;
using lanes::transpose;
static_assert(offsetof(Strut, stiffness) == offsetof(Strut, restLength) + sizeof(double),
              "a strut's rest length and stiffness load as one pair");

struct PacketForce {
  Pair xy[4];     // strut r's (fx, fy)
  double z[4];    // strut r's fz
  unsigned ok;    // bit r: strut r has a direction (its ends do not coincide)
};

__attribute__((always_inline)) inline void strutPacket(const Strut* const s[4], const Vec3* x, const Vec3* v,
                                                       PacketForce& out) {
  Pair dxy[4], wxy[4], lk[4];
  double dz[4], wz[4], d[4];
  for (int r = 0; r < 4; ++r) {
    const Strut& st = *s[r];
    dxy[r] = loadPair(&x[st.j].x) - loadPair(&x[st.i].x);
    wxy[r] = loadPair(&v[st.j].x) - loadPair(&v[st.i].x);
    dz[r] = x[st.j].z - x[st.i].z;
    wz[r] = v[st.j].z - v[st.i].z;
    lk[r] = loadPair(&st.restLength);  // (restLength, stiffness)
    d[r] = st.damping;
  }
  Lanes dx, dy, wx, wy, l0, k;
  transpose(dxy[0], dxy[1], dxy[2], dxy[3], dx, dy);
  transpose(wxy[0], wxy[1], wxy[2], wxy[3], wx, wy);
  transpose(lk[0], lk[1], lk[2], lk[3], l0, k);
  const Lanes dzl = {dz[0], dz[2], dz[1], dz[3]}, wzl = {wz[0], wz[2], wz[1], wz[3]};
  const Lanes dl = {d[0], d[2], d[1], d[3]};
  const Lanes ll = dx * dx + dy * dy + dzl * dzl;
  Lanes len;
  for (int l = 0; l < 4; ++l) len[l] = std::sqrt(ll[l]);  // one vsqrtpd with AVX
  const Lanes inv = 1.0 / len;
  const Lanes ux = dx * inv, uy = dy * inv, uz = dzl * inv;
  const Lanes scale = k * (len - l0) + dl * (wx * ux + wy * uy + wzl * uz);
  const Lanes fx = ux * scale, fy = uy * scale, fz = uz * scale;
  // Back to struts: unpacking (fx, fy) gives the pairs of lanes 0 and 2 (struts 0 and 1), and of
  // lanes 1 and 3 (struts 2 and 3).
  lanes::untranspose(fx, fy, out.xy);
  out.z[0] = fz[0], out.z[1] = fz[2], out.z[2] = fz[1], out.z[3] = fz[3];
  out.ok = (len[0] > 0.0 ? 1u : 0u) | (len[2] > 0.0 ? 2u : 0u) | (len[1] > 0.0 ? 4u : 0u) | (len[3] > 0.0 ? 8u : 0u);
}

// f[i] += (xy, z) or -= it, the pair as one 16-byte operation (the same sums as per component).
inline void addTo(Vec3& f, Pair xy, double z) {
  lanes::storePair(&f.x, loadPair(&f.x) + xy);
  f.z += z;
}
inline void subtractFrom(Vec3& f, Pair xy, double z) {
  lanes::storePair(&f.x, loadPair(&f.x) - xy);
  f.z -= z;
}

// Adds the forces of count struts, the r-th being struts[indexOf(r)], to the ends whose bit is
// set in maskOf(r) (bit 0: i, bit 1: j): four at a time, the rest one at a time, always summed
// in list order. Always inlined: otherwise GCC compiles it once, for the baseline target, and
// both target_clones below call that copy (three times slower than the AVX2 one).
template <class IndexOf, class MaskOf>
__attribute__((always_inline)) inline void applyStrutList(const Strut* struts, std::size_t count, IndexOf indexOf,
                                                          MaskOf maskOf, const Vec3* x, const Vec3* v, Vec3* f) {
  const auto add = [&](std::size_t r, Pair xy, double z) {
    const Strut& st = struts[indexOf(r)];
    const uint32_t mask = maskOf(r);
    if (mask & 1u) addTo(f[st.i], xy, z);
    if (mask & 2u) subtractFrom(f[st.j], xy, z);
  };
  PacketForce packet;
  std::size_t r = 0;
  for (; r + 4 <= count; r += 4) {
    const Strut* s[4] = {&struts[indexOf(r)], &struts[indexOf(r + 1)], &struts[indexOf(r + 2)],
                         &struts[indexOf(r + 3)]};
    strutPacket(s, x, v, packet);
    for (std::size_t l = 0; l < 4; ++l) {
      if (packet.ok & (1u << l)) add(r + l, packet.xy[l], packet.z[l]);
    }
  }
  Vec3 fi;
  for (; r < count; ++r) {
    if (strutForce(struts[indexOf(r)], x, v, fi)) add(r, Pair{fi.x, fi.y}, fi.z);
  }
}

}  // namespace

// Both loops (range and list) are spelt out here rather than through Elements::visit: a lambda
// is compiled once for the baseline target and called from both clones (measured 2.3 times
// slower, even with always_inline on the lambda; GCC 12).
__attribute__((target_clones("avx2", "default"))) void applyStruts(const Strut* struts, Elements elements,
                                                                   const Vec3* x, const Vec3* v, Vec3* f) {
  if (const ElementRef* list = elements.list()) {
    applyStrutList(struts, elements.count(), Elements::ListIndex{list}, Elements::ListMask{list}, x, v, f);
  } else {
    applyStrutList(struts, elements.count(), Elements::RangeIndex{elements.first()}, Elements::AllVertices{}, x, v, f);
  }
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

namespace {

Eigen::Vector3d ev(const Vec3& a) { return {a.x, a.y, a.z}; }

}  // namespace

bool strutJacobian(const Strut& st, const Vec3* x, const Vec3* v, Eigen::Matrix3d& dfdx, Eigen::Matrix3d& dfdv, bool definite) {
  const Vec3 xij = x[st.j] - x[st.i];
  const double l = length(xij);
  if (!(l > 0.0)) return false;
  const Eigen::Vector3d u = ev(xij / l);
  const Eigen::Matrix3d uu = u * u.transpose();
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - uu;
  const double transverse = 1.0 - st.restLength / l;
  dfdx = st.stiffness * uu + st.stiffness * (definite ? std::max(0.0, transverse) : transverse) * P;
  if (!definite) {
    const Eigen::Vector3d vij = ev(v[st.j] - v[st.i]);
    dfdx += (st.damping / l) * (u * (P * vij).transpose() + vij.dot(u) * P);
  }
  dfdv = st.damping * uu;
  return true;
}

std::size_t strutCount(const Model& model) { return model.struts.size(); }

void strutVertices(const Model& model, std::size_t strut, uint32_t* vertices) {
  vertices[0] = model.struts[strut].i;
  vertices[1] = model.struts[strut].j;
}

bool strutBlocks(const Model& model, std::size_t strut, const Vec3* x, const Vec3* v, bool definite, Matrix12& dfdx,
                 Matrix12& dfdv) {
  Eigen::Matrix3d kx, kv;
  if (!strutJacobian(model.struts[strut], x, v, kx, kv, definite)) return false;
  dfdx.block<3, 3>(0, 0) = -kx;
  dfdx.block<3, 3>(0, 3) = kx;
  dfdx.block<3, 3>(3, 0) = kx;
  dfdx.block<3, 3>(3, 3) = -kx;
  dfdv.block<3, 3>(0, 0) = -kv;
  dfdv.block<3, 3>(0, 3) = kv;
  dfdv.block<3, 3>(3, 0) = kv;
  dfdv.block<3, 3>(3, 3) = -kv;
  return true;
}

void strutVbdTerm(const VbdCall& call, std::size_t strut, int slot, Vec3& f, Sym3& H) {
  const Strut& s = call.model.struts[strut];
  const uint32_t i = slot == 0 ? s.i : s.j, j = slot == 0 ? s.j : s.i;
  const Vec3* x = call.x;
  const Vec3 d = x[j] - x[i];
  const double l = length(d);
  if (!(l > 0.0)) return;
  const double invL = 1.0 / l;
  const Vec3 u = d * invL;
  const Vec3 vi = (x[i] - call.x0[i]) * call.invH;
  const Vec3 relative = (x[j] - call.x0[j]) * call.invH - vi;
  f += u * (s.stiffness * (l - s.restLength) + s.damping * dot(relative, u));
  H.addOuter(u, s.stiffness + s.damping * call.invH);
  const double transverse = s.stiffness * std::max(0.0, 1.0 - s.restLength * invL);
  if (transverse > 0.0) {
    H.addDiagonal(transverse);
    H.addOuter(u, -transverse);
  }
}

void strutBoundRows(const Model& model, const Vec3* x, const double* invMass, uint32_t body, RowBound* rows) {
  const BodyInfo& info = model.bodies[body];
  // In products with the inverse masses (0 for a pinned vertex, which adds nothing): this is
  // made again every few steps of an adaptive run, where its divisions and square roots were
  // a fifth of the run.
  for (uint32_t s = info.firstStrut; s < info.firstStrut + info.strutCount; ++s) {
    const Strut& st = model.struts[s];
    // The geometric term |1 - L0/l| passes 1 only below half the rest length.
    const double l2 = lengthSquared(x[st.j] - x[st.i]);
    const double stretch =
        l2 > 0.0 && 4.0 * l2 < st.restLength * st.restLength ? st.restLength / std::sqrt(l2) - 1.0 : 1.0;
    const double k = st.stiffness * stretch, d = st.damping;
    const double ii = invMass[st.i], jj = invMass[st.j], ij = std::sqrt(ii * jj);
    RowBound& ri = rows[st.i - info.firstVertex];
    RowBound& rj = rows[st.j - info.firstVertex];
    ri.strutStiffness += k * (ii + ij);
    ri.strutDamping += d * (ii + ij);
    rj.strutStiffness += k * (jj + ij);
    rj.strutDamping += d * (jj + ij);
  }
}

}  // namespace springy

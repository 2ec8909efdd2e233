#include "sim/forces.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/lanes.h"

namespace springy {
namespace {

using lanes::Lanes;
using lanes::loadPair;
using lanes::Pair;

// The wind's force on each corner of face t; false for a leeward or degenerate face. A face of
// an open surface (a cloth) has no leeward side: the wind meets whichever side faces it, and
// c A ((w - v) . n) n is the same for n and -n.
inline bool windForce(const Triangle& t, double c, const Vec3& air, const Vec3* x, const Vec3* v, bool twoSided,
                      Vec3& force) {
  const Vec3 areaNormal = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]) * 0.5;  // |.| = area
  const Vec3 relative = air - (v[t[0]] + v[t[1]] + v[t[2]]) / 3.0;
  const double flux = dot(relative, areaNormal);  // = A (w - v) . n
  if (twoSided ? flux == 0.0 : flux >= 0.0) return false;  // leeward face (or edge-on)
  const double area = length(areaNormal);
  if (!(area > 0.0)) return false;
  force = areaNormal * (c * flux / area / 3.0);  // c A ((w - v) . n) n / 3
  return true;
}

}  // namespace

void setGravity(const Model& model, std::size_t begin, std::size_t end, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) f[i] = model.gravity * model.mass[i];
}

void applyDrag(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* v, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) f[i] -= (v[i] - air) * (model.drag * model.mass[i]);
}

namespace {

// windForce for four faces at once, one per lane (sim/lanes.h): the same operations in the same
// order, so each face's force is bit-identical to windForce's. Bit r of the result: face r is
// pushed (windForce returned true), its corners' force in force[r].
__attribute__((always_inline)) inline unsigned windPacket(const Triangle* const ts[4], const bool twoSided[4], double c,
                                                          const Vec3& air, const Vec3* x, const Vec3* v,
                                                          Vec3 force[4]) {
  using lanes::V3L;
  V3L p[3], w[3];
  for (int i = 0; i < 3; ++i) {
    const uint32_t index[4] = {(*ts[0])[i], (*ts[1])[i], (*ts[2])[i], (*ts[3])[i]};
    p[i] = lanes::gather(x, index);
    w[i] = lanes::gather(v, index);
  }
  const V3L areaNormal = cross(p[1] - p[0], p[2] - p[0]) * Lanes{0.5, 0.5, 0.5, 0.5};
  const V3L velocity = w[0] + w[1] + w[2];
  const V3L relative = {air.x - velocity.x / 3.0, air.y - velocity.y / 3.0, air.z - velocity.z / 3.0};
  const Lanes flux = dot(relative, areaNormal);
  const Lanes area = lanes::sqrt(dot(areaNormal, areaNormal));
  lanes::scatter(areaNormal * (c * flux / area / 3.0), force);
  unsigned pushed = 0;
  for (int r = 0; r < 4; ++r) {
    const int l = lanes::kLaneOf[r];
    const bool leeward = twoSided[r] ? flux[l] == 0.0 : flux[l] >= 0.0;
    if (!leeward && area[l] > 0.0) pushed |= 1u << r;
  }
  return pushed;
}

// Four faces a packet, the rest one at a time, each face's force added to its corners in list
// order. Always inlined into applyWindPressure's clones (as applyStrutList, strut.cpp).
template <class IndexOf, class MaskOf>
__attribute__((always_inline)) inline void applyWindList(const Model& model, std::size_t count, IndexOf indexOf,
                                                         MaskOf maskOf, const Vec3& air, const Vec3* x, const Vec3* v,
                                                         Vec3* f) {
  const double c = model.wind->pressure;
  const auto add = [&](std::size_t r, const Vec3& force) {
    const Triangle& t = model.faces[indexOf(r)];
    const uint32_t mask = maskOf(r);
    for (int i = 0; i < 3; ++i) {
      if (mask & (1u << i)) f[t[i]] += force;
    }
  };
  const auto open = [&](const Triangle& t) { return model.bodies[model.body[t[0]]].open; };
  Vec3 force[4];
  std::size_t r = 0;
  for (; r + 4 <= count; r += 4) {
    const Triangle* ts[4];
    bool twoSided[4];
    for (std::size_t k = 0; k < 4; ++k) ts[k] = &model.faces[indexOf(r + k)], twoSided[k] = open(*ts[k]);
    const unsigned pushed = windPacket(ts, twoSided, c, air, x, v, force);
    for (std::size_t k = 0; k < 4; ++k) {
      if (pushed & (1u << k)) add(r + k, force[k]);
    }
  }
  for (; r < count; ++r) {
    const Triangle& t = model.faces[indexOf(r)];
    if (windForce(t, c, air, x, v, open(t), force[0])) add(r, force[0]);
  }
}

}  // namespace

// Both loops (range and list) spelt out, as applyStruts (strut.cpp) does and for its reason.
__attribute__((target_clones("avx2", "default"))) void applyWindPressure(const Model& model, Elements faces,
                                                                         const Vec3& air, const Vec3* x, const Vec3* v,
                                                                         Vec3* f) {
  if (const ElementRef* list = faces.list()) {
    applyWindList(model, faces.count(), Elements::ListIndex{list}, Elements::ListMask{list}, air, x, v, f);
  } else {
    applyWindList(model, faces.count(), Elements::RangeIndex{faces.first()}, Elements::AllVertices{}, air, x, v, f);
  }
}

namespace {

// Six times the volume of faces [begin, end) about o; with kStore, also each face's N. Four
// faces at a time, one per lane (sim/lanes.h), each lane summing its own faces; the lanes' sums
// are added in lane order at the end and the faces left over one by one, so the result depends
// only on [begin, end). A vertex's x and y load as one pair. (One face at a time, GCC kept the
// face's N in memory between its store and the dot product, and the loop waited on that round
// trip; one sum in face order, the loop waited on its additions.)
template <bool kStore>
__attribute__((always_inline)) inline double sixVolumeOf(const Triangle* faces, uint32_t begin, uint32_t end,
                                                         const Vec3& o, const Vec3* x, Vec3* areaVectors) {
  Lanes sums = {0.0, 0.0, 0.0, 0.0};
  uint32_t f = begin;
  for (; f + 4 <= end; f += 4) {
    Pair p0[4], p1[4], p2[4];
    double z0[4], z1[4], z2[4];
    for (int r = 0; r < 4; ++r) {
      const Triangle& t = faces[f + static_cast<uint32_t>(r)];
      p0[r] = loadPair(&x[t[0]].x), p1[r] = loadPair(&x[t[1]].x), p2[r] = loadPair(&x[t[2]].x);
      z0[r] = x[t[0]].z, z1[r] = x[t[1]].z, z2[r] = x[t[2]].z;
    }
    Lanes x0, y0, x1, y1, x2, y2;
    lanes::transpose(p0[0], p0[1], p0[2], p0[3], x0, y0);
    lanes::transpose(p1[0], p1[1], p1[2], p1[3], x1, y1);
    lanes::transpose(p2[0], p2[1], p2[2], p2[3], x2, y2);
    const Lanes zl0 = {z0[0], z0[2], z0[1], z0[3]}, zl1 = {z1[0], z1[2], z1[1], z1[3]},
                zl2 = {z2[0], z2[2], z2[1], z2[3]};
    const Lanes e1x = x1 - x0, e1y = y1 - y0, e1z = zl1 - zl0, e2x = x2 - x0, e2y = y2 - y0, e2z = zl2 - zl0;
    const Lanes nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
    const Lanes d = (x0 - o.x) * nx + (y0 - o.y) * ny + (zl0 - o.z) * nz;
    sums += d;
    if constexpr (kStore) {
      Pair nxy[4];
      lanes::untranspose(nx, ny, nxy);
      for (int r = 0; r < 4; ++r) {
        Vec3& n = areaVectors[f + static_cast<uint32_t>(r)];
        lanes::storePair(&n.x, nxy[r]);
        n.z = nz[lanes::kLaneOf[r]];
      }
    }
  }
  double sum = ((sums[0] + sums[1]) + sums[2]) + sums[3];
  for (; f < end; ++f) {
    const uint32_t i0 = faces[f][0], i1 = faces[f][1], i2 = faces[f][2];
    const Vec3 x0 = x[i0], e1 = x[i1] - x0, e2 = x[i2] - x0;
    const Vec3 n = cross(e1, e2);
    sum += dot(x0 - o, n);
    if constexpr (kStore) areaVectors[f] = n;
  }
  return sum;
}

}  // namespace

__attribute__((target_clones("avx2", "default"))) double sixVolume(const Model& model, uint32_t begin, uint32_t end,
                                                                   const Vec3& o, const Vec3* x, Vec3* areaVectors) {
  return areaVectors ? sixVolumeOf<true>(model.faces.data(), begin, end, o, x, areaVectors)
                     : sixVolumeOf<false>(model.faces.data(), begin, end, o, x, nullptr);
}

uint32_t volumeChunkCount(const BodyInfo& body) { return (body.faceCount + kVolumeChunk - 1) / kVolumeChunk; }

double chunkSixVolume(const Model& model, uint32_t body, uint32_t chunk, const Vec3* x) {
  const BodyInfo& info = model.bodies[body];
  const uint32_t begin = info.firstFace + chunk * kVolumeChunk;
  return sixVolume(model, begin, std::min(begin + kVolumeChunk, info.firstFace + info.faceCount),
                   x[info.firstVertex], x);
}

double enclosedVolume(const Model& model, uint32_t body, const Vec3* x) {
  const uint32_t chunks = volumeChunkCount(model.bodies[body]);
  double sum = 0.0;
  for (uint32_t c = 0; c < chunks; ++c) sum += chunkSixVolume(model, body, c, x);
  return sum / 6.0;
}

double gasOverpressure(const BodyInfo& body, double volume) {
  if (!(volume > 0.0)) return std::numeric_limits<double>::infinity();
  return body.gasPressure * (body.restVolume / volume - 1.0);
}

double gasEnergy(const BodyInfo& body, double volume) {
  if (body.gasPressure == 0.0) return 0.0;
  if (!(volume > 0.0)) return std::numeric_limits<double>::infinity();
  const double d = (volume - body.restVolume) / body.restVolume;  // V / V0 - 1, without cancellation
  return body.gasPressure * body.restVolume * (d - std::log1p(d));
}

VertexFaces vertexFaces(const Model& model) {
  VertexFaces around;
  const std::size_t n = model.vertexCount();
  around.start.assign(n + 1, 0);
  for (const Triangle& t : model.faces) {
    for (uint32_t i : t) ++around.start[i + 1];
  }
  for (std::size_t i = 0; i < n; ++i) around.start[i + 1] += around.start[i];
  around.faces.resize(around.start[n]);
  std::vector<uint32_t> next(around.start.begin(), around.start.end() - 1);
  for (uint32_t k = 0; k < model.faces.size(); ++k) {
    for (uint32_t i : model.faces[k]) around.faces[next[i]++] = k;
  }
  return around;
}

void applyGasPressure(const Model& model, const double* overpressure, const VertexFaces& around,
                      const Vec3* areaVectors, std::size_t begin, std::size_t end, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) {
    const double p = overpressure[model.body[i]];
    if (p == 0.0) continue;
    Vec3 sum;
    for (uint32_t k = around.start[i]; k < around.start[i + 1]; ++k) sum += areaVectors[around.faces[k]];
    f[i] += sum * (p / 6.0);
  }
}

void MassMoments::add(const MassMoments& o) {
  mass += o.mass;
  first += o.first;
  momentum += o.momentum;
  angular += o.angular;
  for (int k = 0; k < 6; ++k) second[k] += o.second[k];
}

MassMoments massMoments(const Model& model, std::size_t begin, std::size_t end, const Vec3& o, const Vec3* x,
                        const Vec3* v) {
  MassMoments s;
  for (std::size_t i = begin; i < end; ++i) {
    const double m = model.mass[i];
    const Vec3 r = x[i] - o, mr = r * m;
    s.mass += m;
    s.first += mr;
    s.momentum += v[i] * m;
    s.angular += cross(mr, v[i]);
    s.second[0] += mr.x * r.x, s.second[1] += mr.y * r.y, s.second[2] += mr.z * r.z;
    s.second[3] += mr.x * r.y, s.second[4] += mr.x * r.z, s.second[5] += mr.y * r.z;
  }
  return s;
}

RigidMotion rigidMotion(const MassMoments& s, const Vec3& o) {
  RigidMotion rigid;
  if (!(s.mass > 0.0)) return rigid;
  const Vec3 c = s.first / s.mass;  // centre of mass about o
  rigid.center = o + c;
  rigid.velocity = s.momentum / s.mass;
  // Angular momentum and inertia about the centre of mass.
  const Vec3 angular = s.angular - cross(c, s.momentum);
  const double xx = s.second[0] - s.mass * c.x * c.x, yy = s.second[1] - s.mass * c.y * c.y,
               zz = s.second[2] - s.mass * c.z * c.z, xy = s.second[3] - s.mass * c.x * c.y,
               xz = s.second[4] - s.mass * c.x * c.z, yz = s.second[5] - s.mass * c.y * c.z;
  const double trace = xx + yy + zz;
  // I = trace(S) 1 - S, symmetric: solve I w = L by its adjugate.
  const double a = trace - xx, b = -xy, cc = -xz, d = trace - yy, e = -yz, f = trace - zz;
  const double A = d * f - e * e, B = cc * e - b * f, C = b * e - cc * d;
  const double det = a * A + b * B + cc * C;
  if (!(det > 1e-12 * trace * trace * trace)) return rigid;
  const double D = a * f - cc * cc, E = b * cc - a * e, F = a * d - b * b;
  rigid.spin = Vec3{A * angular.x + B * angular.y + C * angular.z, B * angular.x + D * angular.y + E * angular.z,
                    C * angular.x + E * angular.y + F * angular.z} /
               det;
  return rigid;
}

void applyDeformationDamping(const Model& model, const RigidMotion* rigid, std::size_t begin, std::size_t end,
                             const Vec3* x, const Vec3* v, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) {
    const RigidMotion& r = rigid[model.body[i]];
    if (r.rate == 0.0) continue;
    f[i] -= (v[i] - r.at(x[i])) * (r.rate * model.mass[i]);
  }
}

double dragDamping(const Model& model, uint32_t) { return model.drag; }

double deformationDiagonal(const Model& model, uint32_t vertex) {
  return model.bodies[model.body[vertex]].deformationDamping;
}

void dragVbdTerm(const VbdCall& call, uint32_t i, Vec3& f, Sym3& H) {
  if (!(call.model.drag > 0.0)) return;
  const double c = call.model.drag * call.model.mass[i];
  const Vec3 vi = (call.x[i] - call.x0[i]) * call.invH;
  f -= (vi - call.air) * c;
  H.addDiagonal(c * call.invH);
}

void gasBoundRows(const Model& model, const Vec3* x, const double* invMass, uint32_t body, RowBound* rows) {
  const BodyInfo& info = model.bodies[body];
  if (!(info.gasPressure > 0.0)) return;
  const double sum = volumeModeSum(model, info, x, invMass);
  const double volume = enclosedVolume(model, body, x);
  const double w2 = volume > 0.0 ? info.gasPressure * info.restVolume / (volume * volume) * sum : 0.0;
  for (uint32_t k = 0; k < info.vertexCount; ++k) rows[k].gasStiffness = w2;
}

}  // namespace springy

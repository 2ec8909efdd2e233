#pragma once

// Four doubles in one vector (GCC's vector extension: one AVX register where a function is
// compiled for AVX2, chosen at run time by target_clones, else two SSE2 halves), and the
// helpers the packet kernels share (struts, hinges, the enclosed volume, the wind). Each lane
// performs a scalar kernel's operations in the same order, and the build never fuses a multiply
// and an add (-ffp-contract=off), so each element's result is bit-identical to the scalar
// kernel's whichever lane computes it; a kernel that sums over elements says in which order.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "sim/vec3.h"

// These helpers, and the kernels' own inlined helpers, pass and return 32-byte vectors; GCC's
// note that such calls have another ABI with and without AVX concerns no caller: everything
// using them is inlined into a kernel's clone. Ignored for the files that include this one.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace springy::lanes {

typedef double Lanes __attribute__((vector_size(32)));
typedef double Pair __attribute__((vector_size(16)));

inline Pair loadPair(const double* p) {
  Pair r;
  std::memcpy(&r, p, sizeof r);
  return r;
}
inline void storePair(double* p, Pair value) { std::memcpy(p, &value, sizeof value); }

// Four (x, y) pairs into an x vector and a y vector, with the elements in the order 0, 2, 1, 3:
// the order in which AVX's in-lane unpacks turn four pairs into two vectors.
inline void transpose(Pair p0, Pair p1, Pair p2, Pair p3, Lanes& first, Lanes& second) {
  const Lanes lo = __builtin_shufflevector(p0, p1, 0, 1, 2, 3), hi = __builtin_shufflevector(p2, p3, 0, 1, 2, 3);
  first = __builtin_shufflevector(lo, hi, 0, 4, 2, 6);
  second = __builtin_shufflevector(lo, hi, 1, 5, 3, 7);
}

// The inverse: vectors x and y in transpose's lane order back to element r's (x, y) pair.
inline void untranspose(Lanes x, Lanes y, Pair out[4]) {
  const Lanes even = __builtin_shufflevector(x, y, 0, 4, 2, 6), odd = __builtin_shufflevector(x, y, 1, 5, 3, 7);
  out[0] = __builtin_shufflevector(even, even, 0, 1);
  out[1] = __builtin_shufflevector(even, even, 2, 3);
  out[2] = __builtin_shufflevector(odd, odd, 0, 1);
  out[3] = __builtin_shufflevector(odd, odd, 2, 3);
}

// Element r's lane in transpose's order (the order is its own inverse: lane l holds element
// kLaneOf[l]).
constexpr int kLaneOf[4] = {0, 2, 1, 3};

// Four vectors, one per lane, with Vec3's operations in the same order.
struct V3L {
  Lanes x, y, z;
};
inline V3L operator+(const V3L& a, const V3L& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3L operator-(const V3L& a, const V3L& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3L operator-(const V3L& a) { return {-a.x, -a.y, -a.z}; }
inline V3L operator*(const V3L& a, const Lanes& s) { return {a.x * s, a.y * s, a.z * s}; }
inline Lanes dot(const V3L& a, const V3L& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3L cross(const V3L& a, const V3L& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Lanes sqrt(const Lanes& a) {
  Lanes r;
  for (int l = 0; l < 4; ++l) r[l] = std::sqrt(a[l]);  // one vsqrtpd with AVX
  return r;
}

static_assert(offsetof(Vec3, y) == offsetof(Vec3, x) + sizeof(double), "a Vec3's x and y load as one pair");

// Vectors v[index[r]], r = 0..3, into lanes in transpose's order: x and y as one 16-byte pair.
inline V3L gather(const Vec3* v, const uint32_t index[4]) {
  V3L out;
  transpose(loadPair(&v[index[0]].x), loadPair(&v[index[1]].x), loadPair(&v[index[2]].x), loadPair(&v[index[3]].x),
            out.x, out.y);
  out.z = Lanes{v[index[0]].z, v[index[2]].z, v[index[1]].z, v[index[3]].z};
  return out;
}
// Lane values back to four vectors, element r's into out[r] (transpose's order undone).
inline void scatter(const V3L& a, Vec3 out[4]) {
  Pair xy[4];
  untranspose(a.x, a.y, xy);
  for (int r = 0; r < 4; ++r) {
    storePair(&out[r].x, xy[r]);
    out[r].z = a.z[kLaneOf[r]];
  }
}

}  // namespace springy::lanes

#pragma once

// Four doubles in one vector (GCC's vector extension: one AVX register where a function is
// compiled for AVX2, chosen at run time by target_clones, else two SSE2 halves), and the
// helpers the packet kernels share (struts and hinges, the enclosed volume). Each lane performs
// a scalar kernel's operations in the same order, and the build never fuses a multiply and an
// add (-ffp-contract=off), so each element's result is bit-identical to the scalar kernel's
// whichever lane computes it; a kernel that sums over elements says in which order.

#include <cstring>

// These helpers return 32-byte vectors; GCC's note that such calls have another ABI with and
// without AVX concerns no caller (they are inlined into the kernels).
#pragma GCC diagnostic push
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

// Element r's lane in transpose's order.
constexpr int kLaneOf[4] = {0, 2, 1, 3};

}  // namespace springy::lanes

#pragma GCC diagnostic pop

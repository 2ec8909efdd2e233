// springy tests: a seeded random sequence that is the same with every standard library.
#pragma once

#include <cstdint>
#include <random>

#include "sim/vec3.h"

namespace springy::test {

// Uniform double in [lo, hi) from the raw 32-bit output of mt19937 (no std:: distribution, so
// the sequence is the same with every standard library).
class Random {
 public:
  explicit Random(uint32_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) {
    const uint64_t bits = (static_cast<uint64_t>(engine_()) << 21) ^ static_cast<uint64_t>(engine_());
    const double unit = static_cast<double>(bits & ((uint64_t{1} << 53) - 1)) * 0x1.0p-53;
    return lo + (hi - lo) * unit;
  }
  Vec3 point(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  Vec3 point(const Vec3& lo, const Vec3& hi) { return {uniform(lo.x, hi.x), uniform(lo.y, hi.y), uniform(lo.z, hi.z)}; }
  uint32_t below(uint32_t n) { return static_cast<uint32_t>(engine_() % n); }

 private:
  std::mt19937 engine_;
};

}  // namespace springy::test

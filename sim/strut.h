// springy: damped springs along struts (docs/model.md, eq. S1-S4).
//
//   x_ij = x_j - x_i, l = |x_ij|, u = x_ij / l
//   f_i = k (l - l0) u + d ((v_j - v_i) . u) u,   f_j = -f_i
//
// The dashpot acts only along the strut, so a rigid rotation of the strut feels no damping.
#pragma once

#include <cstddef>

#include "sim/model.h"
#include "sim/parallel.h"

namespace springy {

// Accumulates the forces of the selected struts into f (all of a range, or a thread's list
// adding only to the ends its masks name: bit 0 i, bit 1 j; sim/parallel.h).
void applyStruts(const Strut* struts, Elements elements, const Vec3* x, const Vec3* v, Vec3* f);

// Elastic energy 1/2 k (l - l0)^2 summed over struts [begin, end), and the largest strain
// |l - l0| / l0 among them. The energies are summed in four interleaved partial sums (struts
// begin + 4q + r go to sum r), then the rest one at a time: the same bits for the same range.
struct StrutMeasures {
  double energy = 0.0;
  double maxStrain = 0.0;
};
StrutMeasures measureStruts(const Strut* struts, std::size_t begin, std::size_t end, const Vec3* x);

}  // namespace springy

// springy: damped springs along struts (docs/model.md, eq. S1-S4).
//
//   x_ij = x_j - x_i, l = |x_ij|, u = x_ij / l
//   f_i = k (l - l0) u + d ((v_j - v_i) . u) u,   f_j = -f_i
//
// The dashpot acts only along the strut, so a rigid rotation of the strut feels no damping.
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "sim/kind_types.h"
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

// Jacobian blocks of one strut: dfdx = d f_i / d x_j (then d f_i/d x_i = d f_j/d x_j = -dfdx,
// d f_j / d x_i = dfdx), and likewise dfdv. definite: the positive semidefinite part the
// implicit solvers use, k u u^T + k max(0, 1 - l0/l) (I - u u^T) (Choi & Ko 2002) and the
// dashpot's d u u^T (sim/implicit.h); else exact, with the dashpot's position terms. Returns
// false when the two ends coincide (no direction).
bool strutJacobian(const Strut& strut, const Vec3* x, const Vec3* v, Eigen::Matrix3d& dfdx, Eigen::Matrix3d& dfdv,
                   bool definite);

// The registry's hooks for struts (sim/force_kinds.h): two vertices, i and j, per element.
std::size_t strutCount(const Model& model);
void strutVertices(const Model& model, std::size_t strut, uint32_t* vertices);
bool strutBlocks(const Model& model, std::size_t strut, const Vec3* x, const Vec3* v, bool definite, Matrix12& dfdx,
                 Matrix12& dfdv);
// vbd: the strut's force on its end `slot` with its dashpot at v = (x - x0) / h, and its block
// k u u^T + k max(0, 1 - l0/l) (I - u u^T) + d / h u u^T.
void strutVbdTerm(const VbdCall& call, std::size_t strut, int slot, Vec3& f, Sym3& H);
// Gershgorin rows: k |1 - l0/l| (1 at or above half the rest length) and d, each times
// 1/m_i + 1/sqrt(m_i m_j), on both ends.
void strutBoundRows(const Model& model, const Vec3* x, const double* invMass, uint32_t body, RowBound* rows);

}  // namespace springy

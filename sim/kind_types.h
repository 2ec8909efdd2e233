// springy: the types a force kind's hooks take (sim/force_kinds.h, the registry): each kind's
// file (sim/strut.h, sim/hinge.h, sim/forces.h) declares its hooks with them.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string_view>

#include "sim/model.h"
#include "sim/parallel.h"
#include "sim/sym3.h"

namespace springy {

// In evaluation order (the registry's order).
enum class ForceStage : uint8_t { Gravity, Drag, Wind, Struts, Hinges, Gas, Deformation };
std::string_view forceStageName(ForceStage stage);

struct StageData;  // sim/force_kinds.h

// One evaluation of one stage over one scope: the state, the vertices it writes and the
// elements it walks (all of them on one thread, a thread's lists otherwise).
struct StageCall {
  const Model& model;
  const StageData& data;
  const Vec3* x;
  const Vec3* v;
  Vec3 air;  // the wind's air velocity at this time (0 without wind)
  Vec3* f;
  std::size_t begin, end;  // the vertices written
  Elements struts, hinges, faces;
};

// An element's Jacobian blocks: dfdx(3a + r, 3b + c) = d f_a,r / d x_b,c for its vertices a, b in
// the order elements() gives them (only the first 3n rows and columns are used), and dfdv alike.
using Matrix12 = Eigen::Matrix<double, 12, 12>;

// What a kind's vbd term reads: the iterate x, the positions at the step's start x0 (the
// velocity is (x - x0) / h), 1 / h, the air's velocity.
struct VbdCall {
  const Model& model;
  const Vec3* x;
  const Vec3* x0;
  double invH;
  Vec3 air;
};

// One vertex's row of the Gershgorin bound on the mass-normalised stiffness and damping
// matrices (sim/stability.h gershgorinRows): what each kind adds to it.
struct RowBound {
  uint32_t vertex;
  double strutStiffness = 0, hingeStiffness = 0, strutDamping = 0, hingeDamping = 0, drag = 0;
  // The enclosed gas's breathing mode, omega^2 = (p0 V0 / V^2) sum_j |g_j|^2 / m_j: one
  // eigenvalue of the whole body, added to every row (the largest eigenvalue of a sum is at
  // most the sum of the largest eigenvalues). The pressure's curvature term p d^2V/dx^2 is left
  // out: it vanishes at rest, but in a strongly compressed body the limit is then optimistic
  // (docs/stability.md, "stiff gas": measured 0.3-0.8 of the prediction).
  double gasStiffness = 0;
  // A kind that suggest's parameter scaling (sim/stability.h ParameterScale) does not name.
  double otherStiffness = 0, otherDamping = 0;
};

}  // namespace springy

// springy: torsion (hinge) springs across shared edges (docs/model.md §3, eq. S5-S20, A1-A5).
//
// The hinge edge runs from v0 to v1; v2 is the third vertex of the left face (v0, v1, v2) and
// v3 of the right face (v1, v0, v3), both outward-oriented. With h the unit edge direction,
// n_l, n_r the unit outward normals and r_l, r_r the perpendiculars from the hinge line to v2
// and v3, the signed dihedral angle is
//   theta = atan2((n_l x n_r) . h, n_l . n_r)      (0 when flat, > 0 when convex)
// and its gradient with respect to the four vertices (the directions of the seed's forces,
// docs/model.md eq. S16-S20) is
//   g2 = -n_l / |r_l|,  g3 = -n_r / |r_r|,
//   g1 = -((x02 . h) g2 + (x03 . h) g3) / |x01|,  g0 = -(g1 + g2 + g3).
// The force is f_i = -(k (theta - theta0) + d dtheta/dt) g_i with dtheta/dt = sum g_i . v_i,
// the true rate of change of the angle: it is zero for every rigid motion, so rigid motion
// feels no damping, and the damping power -d (dtheta/dt)^2 never adds energy. (The seed used
// the wing vertices' absolute normal velocities, which damps plain translation: docs/model.md,
// eq. S11-S13 against A2.)
// The forces sum to zero and have zero net torque because g is the gradient of a function
// invariant under rigid motion.
//
// Crushed faces: the exact gradient grows as 1/|r| when a wing vertex nears the hinge line,
// which happens only when a violent impact crushes a triangle (its struts compressed by tens of
// percent), and the angle itself is undefined on the line (the face normal flips across it).
// Below a fifth of its rest lever (Hinge::minLever) the hinge fades out: its energy becomes
// 1/2 k delta^2 S(|r_l|/minLever_l) S(|r_r|/minLever_r), S(u) = 3u^2 - 2u^3 (1 from u = 1 up),
// and the force is exactly minus its gradient, finite however thin the face; the damping uses
// G = S grad(theta). In every ordinary configuration the forces are the exact gradient of
// 1/2 k delta^2 (tested by finite differences, as the faded ones). An earlier guard bounded the
// lever the gradient divides by instead: finite, but not the gradient of any energy, and a
// resting bunny with three permanently crushed faces gained 20 J of motion through it.
#pragma once

#include <cstddef>

#include "sim/kind_types.h"
#include "sim/model.h"
#include "sim/parallel.h"

namespace springy {

struct HingeGeometry {
  double theta;   // signed dihedral angle [rad]
  Vec3 grad[4];   // d theta / d x_i [1/m]
  double leverLeft, leverRight;  // |r_l|, |r_r| [m]
};

// Computes the angle and its gradient. Returns false (and leaves g unset) when the geometry
// is degenerate: a zero-length hinge edge or a wing vertex on the hinge line.
// minLeverLeft/Right bound the lever arms the gradient divides by (see Hinge::minLever): below
// them the "gradient" is the exact one scaled down, so forces stay finite in collapsing faces.
bool hingeGeometry(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, HingeGeometry& g,
                   double minLeverLeft = 0.0, double minLeverRight = 0.0);

// The gradient and lever arms alone, bit-identical to hingeGeometry's (theta: NaN), without
// the angle's atan2: for the stability bounds (sim/stability.h gershgorinRows), which read no angle.
bool hingeGradient(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, HingeGeometry& g,
                   double minLeverLeft = 0.0, double minLeverRight = 0.0);

// Signed dihedral angle alone (the same convention as hingeGeometry).
double dihedralAngle(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

// theta - theta0 wrapped into (-pi, pi], so a hinge folded through +-pi is not kicked by 2 pi.
double angleDifference(double theta, double restAngle);

// Per-hinge constants the force kernel derives once from a Hinge (World keeps them beside the
// hinges): cos and sin of the rest angle, so the kernel gets theta - theta0 without atan2 in the
// common case, and the lever-arm bounds squared and inverted (infinity when unbounded).
struct HingeTerms {
  double restCos, restSin;
  double minLeverSquared[2];
  double invMinLever[2];
};
HingeTerms hingeTerms(const Hinge& hinge);

// Accumulates the forces of the selected hinges into f (all of a range, or a thread's list adding
// only to the vertices its masks name; sim/parallel.h); terms[k] belongs to hinges[k]. Degenerate
// hinges are skipped for the instant (the stated guard; they are rejected at load when
// degenerate at rest).
void applyHinges(const Hinge* hinges, const HingeTerms* terms, Elements elements, const Vec3* x, const Vec3* v,
                 Vec3* f);

// Elastic energy 1/2 k (theta - theta0)^2 summed over hinges [begin, end).
double hingeEnergy(const Hinge* hinges, std::size_t begin, std::size_t end, const Vec3* x);

// Hessian of the dihedral angle, H(3i + a, 3j + b) = d^2 theta / d x_i,a d x_j,b for the four
// hinge vertices in hinge order. Returns false for degenerate geometry. With g_i = d theta / d x_i
// as above, written g2 = G(h, x2 - x0), g3 = -G(h, x3 - x0) with G(h, a) = -(h x a) / (|a|^2 -
// (a.h)^2), g1 = -((x02.h) g2 + (x03.h) g3) / l and g0 = -(g1 + g2 + g3), it follows by the chain
// rule through h = (x1 - x0) / l: an independent derivation of the same quantity as Tamstorf &
// Grinspun 2013, "Discrete bending forces and their Jacobians", in the form that matches this
// gradient.
bool dihedralHessian(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, Matrix12& hessian);

// Jacobians of one hinge's forces on its four vertices: dfdx(3i + a, 3j + b) = d f_i,a / d x_j,b,
// and d f / d v. definite: -k g g^T for dfdx (Gauss-Newton), else exact. Returns false for
// degenerate geometry.
bool hingeJacobian(const Hinge& hinge, const Vec3* x, const Vec3* v, Matrix12& dfdx, Matrix12& dfdv, bool definite);

// The registry's hooks for hinges (sim/force_kinds.h): four vertices per element, in hinge order.
std::size_t hingeCount(const Model& model);
void hingeVertices(const Model& model, std::size_t hinge, uint32_t* vertices);
bool hingeBlocks(const Model& model, std::size_t hinge, const Vec3* x, const Vec3* v, bool definite, Matrix12& dfdx,
                 Matrix12& dfdv);
// vbd: the force on the hinge's vertex in `slot` with its damping at v = (x - x0) / h, and the
// Gauss-Newton block (k + d / h) g g^T of that vertex's g = d theta / d x.
void hingeVbdTerm(const VbdCall& call, std::size_t hinge, int slot, Vec3& f, Sym3& H);
// Gershgorin rows: k and d times w_a sum_b w_b, w = |g| / sqrt(m) (0 for a pinned vertex).
void hingeBoundRows(const Model& model, const Vec3* x, const double* invMass, uint32_t body, RowBound* rows);

}  // namespace springy

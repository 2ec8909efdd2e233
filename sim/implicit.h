// springy: the implicit integrator, backward Euler with Newton iterations and conjugate
// gradients over the analytic Jacobians of the strut, hinge and gas forces (Baraff & Witkin 1998,
// "Large steps in cloth simulation").
//
// One step solves for the end-of-step velocity v1
//   R(v1) = M (v1 - v0) - h f(x0 + h v1, v1, t + h) = 0,        x1 = x0 + h v1
// by Newton's method: (M - h D - h^2 K) dv = -R with K = df/dx, D = df/dv at the current
// iterate. The first iteration from v1 = v0 is exactly Baraff & Witkin's linearised step;
// further iterations converge to the backward Euler solution. The linear system is solved by
// preconditioned conjugate gradients (Jacobi preconditioner) on a sparse matrix whose pattern
// (one 3x3 block per vertex pair that shares a strut or a hinge) is built once; pinned
// vertices (invMass 0) are held by filtering their rows in CG (Baraff & Witkin section 5.3).
//
// CG needs a symmetric positive definite matrix, and the exact K is neither (a compressed
// strut's transverse stiffness k (1 - l0/l) is negative; the hinge's k (theta - theta0) times
// the Hessian of theta is indefinite; the dampers' position terms are not symmetric). The
// solver therefore iterates with the definite part: strut k u u^T + k max(0, 1 - l0/l) (I - u u^T)
// (Choi & Ko 2002), hinge k g g^T (Gauss-Newton) and the exact damping Jacobians D. Newton's
// fixed point, the backward Euler step, does not depend on that choice; only the convergence
// rate does. Each force kind gives its own Jacobian blocks (sim/force_kinds.h: strutJacobian in
// strut.h, hingeJacobian and the dihedral angle's Hessian in hinge.h, exact with definite =
// false, checked against finite differences by the tests); the solver assembles them over the
// registry's kinds that have elements, the kinds' diagonal damping (drag, the deformation
// damping's local part), and the gas as a rank-one term of its own.
//
// Contact inside the solve: with a large step, projecting a vertex back onto a collider after
// the step would move it by up to a step's travel (0.23 m for 14 m/s at 1/60 s) against its
// springs and inject their energy. So, before the solve, every vertex whose predicted path
// (x0 + h (v0 + h a0), a0 from the explicit forces) hits a collider gets a constraint: its
// end-of-step velocity along the hit normal n is the one that lands it on the surface,
// v1 . n = ((p - x0) . n) / h. Newton starts from a guess that obeys the constraints and
// filters every update as for pinned vertices (Baraff & Witkin section 5.3: their prescribed
// change z, applied once to the guess), so the springs respond to the contact within the
// implicit step. World's collide stage still runs
// after the step and applies restitution and friction to what arrives. No allocation inside a step: every buffer and the
// matrix pattern are sized in the constructor.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <cstdint>
#include <utility>
#include <vector>

#include "sim/force_kinds.h"
#include "sim/model.h"

namespace springy {

class Forces;

struct ImplicitSettings {
  int maxNewton = 10;           // Newton iterations per step
  double newtonTolerance = 1e-9;  // stop when |R| <= tol |R_0| ...
  double velocityTolerance = 1e-4;  // ... or max |dv| <= tol (max |v| + |g| dt)
  int maxCg = 1000;             // CG iterations per Newton iteration
  double cgTolerance = 1e-10;   // relative residual of the preconditioned CG
  int maxHalvings = 3;          // an unconverged step is retried as two halves, this deep
};

struct ImplicitStats {
  uint64_t steps = 0;
  uint64_t newtonIterations = 0;
  uint64_t cgIterations = 0;
  uint64_t unconvergedSteps = 0;  // Newton stopped at maxNewton (also counts retried halves)
  uint64_t halvedSteps = 0;       // steps (or halves) retried as two halves
  uint64_t contactConstraints = 0;  // vertex contacts imposed inside the solve
};

class ImplicitSolver {
 public:
  explicit ImplicitSolver(const Model& model, ImplicitSettings settings = {});

  // Advances x, v (the World's state) by dt. When Newton does not converge within maxNewton
  // iterations the step is retried as two half steps, recursively up to maxHalvings deep;
  // returns false if even the smallest pieces did not converge (their last iterate is kept;
  // a non-finite state is left for the stability monitor to report).
  bool step(const Forces& forces, std::vector<Vec3>& x, std::vector<Vec3>& v, double t, double dt);

  // Assembles K = df/dx and D = df/dv over all struts, hinges and drag at (x, v).
  void assemble(const Model& model, const Vec3* x, const Vec3* v, bool definite);
  const Eigen::SparseMatrix<double>& stiffness() const { return K_; }
  const Eigen::SparseMatrix<double>& dampingMatrix() const { return D_; }
  const ImplicitStats& stats() const { return stats_; }

 private:
  // Value index of entry (3a, 3b + c) in the compressed pattern, c = 0..2.
  struct Block {
    int index[3];
  };
  Block findBlock(uint32_t a, uint32_t b) const;
  static void addBlock(Eigen::SparseMatrix<double>& m, const Block& blk, const Eigen::Matrix3d& values, double scale);
  bool stepWithin(const Forces& forces, std::vector<Vec3>& x, std::vector<Vec3>& v, double t, double dt, int depth);
  // One backward Euler step by Newton's method; returns whether it converged.
  bool solve(const Forces& forces, std::vector<Vec3>& x, std::vector<Vec3>& v, double t, double dt);
  // Evaluates rhs_ = -R(v) (filtered) for the step from x0; returns |R|.
  double residual(const Forces& forces, const std::vector<Vec3>& x0, const std::vector<Vec3>& v, double t, double dt);
  // Solves A dv = rhs_ by filtered Jacobi-preconditioned CG; returns the iteration count.
  int solveCg(double absoluteFloor);
  // Removes the constrained components of a vector: pinned vertices entirely, contact vertices
  // along their contact normal.
  void project(Eigen::VectorXd& vec) const;
  // The gas's stiffness for the solver at positions x: for each body with gas, its volume
  // gradient g (in gasGradient_) and c = h^2 p0 V0 / V^2, so that A gains c g g^T (the
  // definite, rank-one part of -h^2 dF/dx; the indefinite p d^2V/dx^2 is left out, as the
  // hinges' curvature term is).
  void assembleGas(const Model& model, const Vec3* x, double dt);
  // q += sum over gas bodies of c g (g . p).
  void addGasProduct(const Eigen::VectorXd& p, Eigen::VectorXd& q) const;
  // Finds the vertices whose predicted path hits a collider and sets their constraints.
  void findContacts(const Forces& forces, const std::vector<Vec3>& x0, double t, double dt);

  ImplicitSettings settings_;
  ImplicitStats stats_;
  std::size_t n_;
  Eigen::SparseMatrix<double> K_, D_, A_;
  std::vector<Block> diagonal_;  // per vertex
  // The model's force kinds with elements and a Jacobian (sim/force_kinds.h), in the registry's
  // order, each with its elements' blocks: per element, (a, b) row-major over its vertices.
  struct KindBlocks {
    const ForceKind* kind;
    std::vector<Block> blocks;
  };
  std::vector<KindBlocks> kinds_;
  std::vector<ForceStage> stages_;  // the model's stage list (the diagonal damping's kinds)
  // Workspace.
  std::vector<Vec3> x1_, f_, v0_, vTrial_;
  Eigen::VectorXd rhs_, dv_, r_, z_, p_, q_, precond_, filter_;
  std::vector<std::vector<Vec3>> xSaved_, vSaved_;  // state before each halving level
  std::vector<uint32_t> contacts_;     // vertices with a contact constraint this step
  std::vector<Vec3> contactNormal_;    // per vertex (meaningful for contacts_)
  std::vector<double> contactSpeed_;   // prescribed v1 . n per vertex
  std::vector<uint32_t> gasBodies_;    // bodies that hold gas
  std::vector<std::pair<Eigen::Index, Eigen::Index>> gasRange_;  // per gas body: first row, rows
  std::vector<double> gasCoefficient_;  // per gas body: h^2 p0 V0 / V^2
  Eigen::VectorXd gasGradient_;        // dV/dx of each gas body's vertices (0 elsewhere)
  std::vector<Vec3> gasScratch_;       // one body's gradient, per vertex
};

}  // namespace springy

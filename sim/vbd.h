// springy: Vertex Block Descent, a large-step implicit integrator (Chen, Ye, Kim & Yuksel 2024,
// "Vertex Block Descent", ACM Trans. Graph. 43(4), 116).
//
// A step of h minimises backward Euler's incremental potential over the end positions x,
//   G(x) = sum_i m_i / (2 h^2) |x_i - y_i|^2 + E(x) + the dampers' dissipation,
//   y_i = x0_i + h v0_i + h^2 a_i (a: gravity and the forces taken at the step's start),
// not by a global Newton solve (sim/implicit.h) but by block coordinate descent: one vertex at
// a time, a Newton step on its own 3x3 block with the others held,
//   H_i dx_i = f_i,  f_i = -(m_i / h^2)(x_i - y_i) + the forces on i,
//   H_i = m_i / h^2 I + the definite part of the force Jacobians' (i, i) block,
// swept `iterations` times over the vertices in colours (greedy, in index order, of the graph
// "shares a strut, a hinge or a face"), so a colour's vertices are independent and are updated
// together, on any number of threads, with the same result. v = (x - x0) / h at the end.
//
// The terms of H_i, each positive semidefinite so that every block solve is a descent step, each
// from its force kind's vbd term (sim/force_kinds.h; the gas's below, here):
//   strut (Choi & Ko 2002's definite part, as the implicit solver's): k u u^T + k max(0, 1 - l0/l)
//     (I - u u^T), its dashpot d / h u u^T (the damping force with v = (x - x0) / h);
//   hinge (Gauss-Newton): (k + d / h) g_i g_i^T, g_i = d theta / d x_i;
//   gas: p0 V0 / V^2 g g^T with g = dV/dx_i (V is affine in each single vertex: d^2V/dx_i^2 = 0,
//     so this is the exact block). The gas couples a colour's vertices through the volume they
//     share: the colour's system is its blocks plus p0 V0 / V^2 G G^T, solved exactly by
//     Sherman-Morrison; and because no two vertices of a colour share a face, the volume after
//     the colour is exactly V + sum g_i . dx_i (summed in colour order);
//   drag: c m / h I.
// Wind and the deformation damping are taken at the step's start (explicit, inside a): they
// act on the body's slow motion, far below the step's limit.
//
// Contact: a vertex whose inertial path x0 -> y hits a static collider gets the constraint
// n . (x_i - p) >= 0 (p the hit point, n its normal) inside its block solve: when the Newton
// step would cross, the step is the one that minimises the block's quadratic on the surface
// (a Lagrange multiplier along n). World's collide stage then applies restitution and friction
// to the velocity it arrived with (arrive()).
//
// What it costs and gives: each sweep costs about two explicit force evaluations (a strut is
// visited from both ends, with its Hessian block); the step is bounded by accuracy, not by the
// stiffest mode. Too few sweeps leave the solve unconverged, which behaves as extra damping
// and softness: docs/accuracy-contact.md and docs/bench-bullet.md measure both.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/force_kinds.h"
#include "sim/forces.h"
#include "sim/model.h"
#include "sim/sym3.h"

namespace springy {

class Forces;

struct VbdStats {
  uint64_t steps = 0;
  uint64_t sweeps = 0;               // sweeps over all colours
  uint64_t contactConstraints = 0;   // vertex contacts imposed inside the solve
  uint64_t activeConstraints = 0;    // block solves that ended on a collider's surface
};

class VbdSolver {
 public:
  static constexpr int kDefaultIterations = 8;
  explicit VbdSolver(const Model& model, int iterations = kDefaultIterations);

  // Advances x, v by dt from time t (forces: the world's stages and threads).
  void step(const Forces& forces, std::vector<Vec3>& x, std::vector<Vec3>& v, double t, double dt);

  // After a step: a vertex held on a collider's surface inside the solve ends on it with the
  // velocity the solve gives, whose normal part is only what was left of the step's travel
  // before the surface. Restitution and friction must act on the velocity the surface stopped:
  // this gives vertex i, along the normal, its solved velocity less the contact's impulse (the
  // force its block presses on the surface with at the solve's end, times h / m: inertia,
  // gravity and the springs pressing it on), and puts it just behind the surface, so that the colliders'
  // response (World's collide stage: restitution, friction on that normal impulse, the resting
  // window) treats it as an explicit step's crossing. Others: unchanged.
  void arrive(uint32_t i, Vec3& x, Vec3& v) const;

  int iterations() const { return iterations_; }
  void setIterations(int iterations) { iterations_ = iterations; }
  std::size_t colours() const { return colourStart_.empty() ? 0 : colourStart_.size() - 1; }
  // The vertices of colour c (ascending).
  const uint32_t* colour(std::size_t c, std::size_t& count) const {
    count = colourStart_[c + 1] - colourStart_[c];
    return colourVertices_.data() + colourStart_[c];
  }
  const VbdStats& stats() const { return stats_; }

 private:
  // Vertex i's block: the force f_i (the gas's at the current overpressure included) and the
  // Hessian H_i without the gas's term, and dV/dx_i of its gas body (0 without one).
  void blockSystem(uint32_t i, const Vec3* x, double h, Vec3& force, Sym3& hessian, Vec3& gradient) const;
  // The held vertices' arrival velocities along their normals (arrive()) at the solve's end x.
  void findArrivals(const Vec3* x, double h);
  // The step dx of vertex i at xi, held on the surface of its contact if it has one.
  Vec3 constrain(uint32_t i, const Vec3& xi, const Sym3& hessian, Vec3 dx) const;
  // The forces taken at the step's start (gravity, wind, deformation damping) into accel_.
  void startAccelerations(const Vec3* x, const Vec3* v, double t);
  // Colours: greedy in index order over "shares an element or a face" (colourStart_, colourVertices_).
  void colourVertices(const Model& model);
  // The inertial prediction y = x0 + h (v0 + h a) as the first guess, each vertex whose path
  // there hits a collider held on its surface.
  void predict(Vec3* x, const Vec3* v, double dt);
  // Gas body k's stiffness p0 V0 / V^2 and overpressure at its current volume.
  void updateGas(std::size_t k);
  // One colour's block solves: each vertex alone, or with a gas the colour's system at once.
  void sweepColour(const Forces& forces, const uint32_t* list, std::size_t count, Vec3* x, double dt);
  void sweepColourWithGas(const Forces& forces, const uint32_t* list, std::size_t count, Vec3* x, double dt);

  const Model* model_;
  int iterations_;
  std::size_t n_;
  // The model's force kinds with a vbd term (sim/force_kinds.h), in the registry's order; for
  // a kind with elements, the elements around each vertex, compressed: vertex i's are
  // list[start[i]] to list[start[i + 1] - 1], each element * size + the vertex's slot in it.
  struct KindTerms {
    const ForceKind* kind;
    std::vector<uint32_t> start, list;
  };
  std::vector<KindTerms> kinds_;
  VertexFaces faces_;  // per vertex, its faces (for the gas)
  std::vector<uint32_t> colourStart_, colourVertices_;
  std::vector<int32_t> gasSlot_;  // per body: its index in volume_, or -1
  std::vector<uint32_t> gasBodies_;
  // Per step.
  std::vector<Vec3> x0_, y_, accel_;
  std::vector<double> dVolume_;
  std::vector<double> volume_, stiffness_, overpressure_;  // per gas body: V, p0 V0 / V^2, p0 (V0 / V - 1)
  std::vector<double> sumA_, sumB_, factor_;                // per gas body, for a colour's solve
  std::vector<Vec3> a_, b_, gradient_;                      // per vertex, with a gas: D^-1 f, D^-1 g, g
  std::vector<double> ga_, gb_;
  std::vector<Sym3> hessian_;
  std::vector<uint8_t> constrained_;
  std::vector<double> arrival_;  // per held vertex: its normal velocity without the surface (NaN: none)
  std::vector<Vec3> contactPoint_, contactNormal_;
  std::vector<RigidMotion> rigid_;
  Vec3 air_;
  double h_ = 0.0;  // the step being taken
  const double* invMass_ = nullptr;  // the World's inverse masses in this step (a released pin moves)
  VbdStats stats_;
};

}  // namespace springy

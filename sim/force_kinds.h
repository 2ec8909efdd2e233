// springy: the registry of force kinds. One row per kind (forceKinds(), sim/force_kinds.cpp), in
// evaluation order, naming what every solver asks of that kind:
//   used            whether a model needs it (only then is it in the model's stage list)
//   force           its forces, for the explicit integrators (sim/force_stages.h Forces)
//   diagonalDamping its -c m_i on the diagonal of df/dv (drag; the deformation damping's local part)
//   elements        the elements it acts through (up to four vertices each: a strut, a hinge), for
//                   the implicit solvers' sparsity, vbd's per-vertex lists and its colours
//   jacobian        an element's blocks of df/dx and df/dv (backward Euler, sim/implicit.h)
//   vbdElement,     its term of a vertex's block: the force on the vertex and the definite part of
//   vbdVertex       the Hessian's (i, i) block (vertex block descent, sim/vbd.h)
//   boundRows       its part of each vertex's Gershgorin row: the stiffness and damping rates that
//                   bound the stable step (the advisor, sim/stability.h)
// A kind's code lives in its own file (sim/strut.*, sim/hinge.*, and sim/forces.* for gravity,
// drag, wind, the gas and the deformation damping); the solvers loop over the model's stage list
// and call these. Adding a force kind: its file, a ForceStage value and one row here, and its
// scene keys (scene/scene.cpp) with the model's data (sim/model.h); docs/model.md walks one
// through. What each solver leaves to a kind it does not need: a null entry.
//
// Two things stay with the solvers: the gas couples every vertex of its body through the volume,
// so the implicit solvers take it as a rank-one term of its own (backward Euler: assembleGas; vbd:
// the colour's exact solve by Sherman-Morrison), not as elements; and vbd takes gravity, wind and
// the deformation damping's rigid part at the step's start (explicit).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/kind_types.h"
#include "sim/strut.h"

namespace springy {

// What the stages read besides the model and the state, derived once from the model (the
// constant parts) and per evaluation (the per-body sums): the stage kernels' inputs.
struct StageData {
  std::vector<HingeTerms> hingeTerms;  // per hinge: the force kernel's constants
  std::vector<uint32_t> gasBodies;     // bodies that hold gas
  VertexFaces facesAround;             // the gas stage's faces per vertex
  std::vector<double> overpressure;    // per body, for the evaluation under way [Pa]
  std::vector<Vec3> areaVectors;       // per face of a gas body: N of sixVolume, same evaluation
  std::vector<RigidMotion> rigid;      // per body (rate 0: not damped), same evaluation
  bool damped = false;                 // a body has deformation damping
};

struct ForceKind {
  ForceStage stage;
  std::string_view name;
  bool (*used)(const Model&);
  // Adds (gravity: sets) its forces on [call.begin, call.end) or its elements' share.
  void (*force)(const StageCall&);
  // Its c in -c m_i on the diagonal of df/dv at vertex i (0: none there).
  double (*diagonalDamping)(const Model&, uint32_t vertex) = nullptr;
  // Its elements: how many vertices each has (at most 4; 0: a kind without elements), how many
  // there are, and the vertices of element e in order.
  int elementSize = 0;
  std::size_t (*elementCount)(const Model&) = nullptr;
  void (*elementVertices)(const Model&, std::size_t element, uint32_t* vertices) = nullptr;
  // Element e's Jacobian blocks at (x, v); definite: the positive semidefinite part the
  // solvers iterate with (sim/implicit.h). False when its geometry is degenerate (skipped).
  bool (*jacobian)(const Model&, std::size_t element, const Vec3* x, const Vec3* v, bool definite, Matrix12& dfdx,
                   Matrix12& dfdv) = nullptr;
  // vbd: element e's term on its vertex in `slot` (its index in elementVertices), or a
  // vertex-local kind's term on vertex i: adds to the force f and the block H.
  void (*vbdElement)(const VbdCall&, std::size_t element, int slot, Vec3& f, Sym3& H) = nullptr;
  void (*vbdVertex)(const VbdCall&, uint32_t vertex, Vec3& f, Sym3& H) = nullptr;
  // Adds its rates to body b's rows (rows[k]: the body's vertex firstVertex + k) at positions x,
  // with the inverse masses invMass (a run's: its released pins move).
  void (*boundRows)(const Model&, const Vec3* x, const double* invMass, uint32_t body, RowBound* rows) = nullptr;
};

// Every kind, in evaluation order: forceKinds()[k].stage is ForceStage value k.
std::span<const ForceKind> forceKinds();
inline const ForceKind& forceKind(ForceStage stage) { return forceKinds()[static_cast<std::size_t>(stage)]; }

// The kinds a model uses (its stage list), in evaluation order.
std::vector<ForceStage> stagesOf(const Model& model);

// The sum of the kinds' diagonal damping at vertex i (drag, then the deformation damping's),
// over the stages given.
double diagonalDamping(const Model& model, const std::vector<ForceStage>& stages, uint32_t vertex);

}  // namespace springy

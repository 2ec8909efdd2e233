// springy: the world a scene builds, and its time step.
//
// The step reads as one ordered list of stages (Box2D's solver stages, MuJoCo's mj_forward):
//   forces:    Forces (sim/force_stages.h): [gravity] [drag] [wind] [struts] [hinges] [gas]
//              [deformation damping], evaluated 1-4 times per step
//   integrate: one function per integrator advances positions and velocities by dt
//   collide:   [static colliders] [damping layers] (continuous, earliest hit wins), in the
//              integrator's last pass over the vertices (lastPass: one fork-join for both);
//              Verlet (fixed and adaptive) resolves them on the drifted positions instead,
//              before the forces there are evaluated
//   contact:   [bodies] between bodies and within a body (sim/contact.h), over the whole step's
//              paths, when two bodies or a self-contact body are in the scene
// A stage is in the list only if the scene uses it: no wind stage without wind, no hinge stage
// for the legacy all-pairs model, no collision pass without colliders. An unused feature costs
// nothing per step.
//
// Model (immutable) and state (positions, velocities, time) are separate; all scratch space
// (force buffers, integrator stages, threads' work lists) is allocated once, never inside a
// step.
//
// Threads (setThreads): force evaluation is split by vertex ownership and the per-vertex loops
// by index ranges (sim/parallel.h), so every thread count gives bit-identical results.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "sim/adaptive_step.h"
#include "sim/contact.h"
#include "sim/drivers.h"
#include "sim/force_stages.h"
#include "sim/integrators.h"
#include "sim/model.h"
#include "sim/state.h"

namespace springy {

class ImplicitSolver;
class VbdSolver;

class World {
 public:
  World(Model model, Integrator integrator, double dt);
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  // Advances the state by one step of dt (the adaptive integrator: one accepted step, of the
  // size its tolerance allows, never past the stop set by stepToward).
  void step();
  // One step toward `time`: the adaptive integrator lands on it exactly; a fixed step is dt.
  void stepToward(double time) {
    adaptive_.setStop(time);
    step();
  }
  // Whether the state has reached `time`: exactly for the adaptive step, within half a step for
  // a fixed one.
  bool reached(double time) const { return adaptive() ? state_.time >= time : state_.time >= time - 0.5 * dt_; }

  // The adaptive integrator (Bogacki-Shampine 3(2), Integrator::BogackiShampine). Each step's
  // local error is estimated twice: by the embedded second-order solution (the difference of
  // the two, in positions) and, for each vertex about to hit a static collider, by the part of
  // the step it would spend stopped at the surface instead of rebounding (|v_n| (1 - s) h: the
  // collision is resolved at the end of the step, so that is what it misplaces). A step whose
  // largest error exceeds `tolerance` times the vertex's body size is taken again, shorter; the
  // next step follows a PI controller (Gustafsson; Hairer & Wanner, Solving ODEs II, IV.2) with
  // safety factor 0.9. Contact between bodies is resolved after a step is accepted; the velocity
  // change it makes bounds the next step the same way. Every decision is a maximum over
  // vertices, so the step sequence is bit-identical on any thread count. dt() is the next step.
  bool adaptive() const { return isAdaptive(integrator_); }
  void setTolerance(double tolerance);
  double tolerance() const { return adaptive_.tolerance(); }
  const StepStats& stepStats() const { return adaptive_.stats(); }
  // Non-empty when the adaptive step could not meet its tolerance above kMinAdaptiveStep (the
  // run must stop; the message says when and what to try).
  const std::string& stepProblem() const { return adaptive_.problem(); }
  static constexpr double kMinAdaptiveStep = AdaptiveStep::kMinStep;  // [s]
  // The adaptive step never exceeds this fraction of the stable step of its stiffest mode at the
  // current shape (updated every 4 steps and at every stop: a compressed body is stiffer). The
  // embedded estimate alone let a mode grow from round-off while it was still too small to see
  // (the hanging sphere's energy rose within 0.07 s at tolerance 1e-3).
  static constexpr double kStableFraction = AdaptiveStep::kStableFraction;

  // Runs the step on up to `requested` threads (the calling thread included). Fewer are used
  // when the model has under `minVerticesPerThread` vertices per thread: below about that the
  // fork-join overhead eats the gain (the measured speed-ups per size are in docs/benchmarks.md).
  // Results are bit-identical for every count.
  static constexpr std::size_t kMinVerticesPerThread = 1000;
  void setThreads(unsigned requested, std::size_t minVerticesPerThread = kMinVerticesPerThread) {
    forces_->setThreads(requested, minVerticesPerThread);
  }
  unsigned threads() const { return forces_->threads(); }
  // Elements evaluated per force evaluation over all threads, divided by the element count:
  // 1 with one thread, slightly above with more (elements on a boundary between threads).
  double redundancy() const { return forces_->redundancy(); }

  // Runs fn(begin, end) over [0, n) split into contiguous ranges among the world's threads,
  // the calling thread included (fork-join); for passes outside the step, such as the
  // measurements. fn must not throw.
  template <class F>
  void parallelFor(std::size_t n, F&& fn) const {
    forces_->parallelFor(n, fn);
  }

  // Total force on every vertex for a given state and time, running the stage list.
  void computeForces(const Vec3* x, const Vec3* v, double t, Vec3* f) const { forces_->evaluate(x, v, t, f); }
  const Forces& forces() const { return *forces_; }

  const Model& model() const { return *model_; }
  Integrator integrator() const { return integrator_; }
  double dt() const { return dt_; }  // the step (the adaptive integrator's: the last one taken)
  double time() const { return state_.time; }
  uint64_t stepCount() const { return state_.steps; }
  // Force evaluations so far by the explicit integrators (the work a step costs; backward
  // Euler's solver evaluates through its own path and is not counted).
  uint64_t forceEvaluations() const { return evaluations_; }
  // Whether vertex i is resting on a static collider: it touched one within the colliders'
  // resting window (Colliders::restingWindow). For drawing (a smooth surface stays flat there).
  bool restsOnCollider(std::size_t i) const { return !sinceContact_.empty() && restingAt(i); }
  // Whether vertex i touches something: it rests on a static collider, or had a contact with a
  // body (another, or its own) in the last step. For exports.
  bool touching(std::size_t i) const { return restsOnCollider(i) || (contacts_ && contacts_->touching(i)); }
  const std::vector<Vec3>& positions() const { return state_.x; }
  const std::vector<Vec3>& velocities() const { return state_.v; }
  // Per vertex, 1 / m or 0 while held: the model's, as the run releases its pins (State::invMass).
  const std::vector<double>& inverseMasses() const { return state_.invMass; }
  const State& state() const { return state_; }
  const std::vector<ForceStage>& forceStages() const { return forces_->stages(); }
  bool collides() const { return !model_->colliders.empty(); }
  // The backward Euler solver (its statistics), or null for the explicit integrators.
  const ImplicitSolver* implicitSolver() const { return implicit_.get(); }
  // The vertex block descent solver (its sweeps per step: setIterations), or null.
  const VbdSolver* vbdSolver() const { return vbd_.get(); }
  void setIterations(int iterations);
  // The contact stage between and within bodies, or null when the scene needs none.
  const BodyContacts* bodyContacts() const { return contacts_.get(); }
  BodyContacts* bodyContacts() { return contacts_.get(); }

  // The state at one instant, for measuring energy. Symplectic Euler's velocity
  // v(n+1) = v(n) + h a(x(n)) belongs to the half step t(n) + h/2, not to its positions x(n+1);
  // an energy of that pair swings by a factor up to (1 - h omega/2)^-1 about the energy the
  // method keeps (a mode of frequency omega: 10x at 0.9 of the stable step), which reads as an
  // instability where there is none. After such a step this gives x(n) (xOld, or x - h v without
  // contacts, which is the same) with v(n+1) - h/2 a(x(n)): velocity Verlet's state at t(n) (the
  // two methods are one, shifted by half a step), whose energy never exceeds the one the method
  // keeps. Returns false, leaving x and v alone, when the state is synchronized as it is.
  bool synchronizedState(std::vector<Vec3>& x, std::vector<Vec3>& v) const;

  // Replaces the state (e.g. a test's initial condition), copying it into the buffers that
  // positions() and velocities() return (their data never moves). Sizes must match the model.
  void setState(std::vector<Vec3> x, std::vector<Vec3> v, double time = 0.0);

 private:
  void accelerations(const Vec3* x, const Vec3* v, double t, Vec3* a) const {
    ++evaluations_;
    forces_->accelerations(x, v, t, a);
    if (!model_->attachments.empty()) addAttachments(x, v, t, a);
  }
  // Adds the soft attachments' forces (Model::attachments) to the accelerations.
  void addAttachments(const Vec3* x, const Vec3* v, double t, Vec3* a) const;
  // Runs fn(begin, end) over [0, vertexCount) split among the threads.
  template <class F>
  void forVertices(F&& fn) const;
  // The step's last pass over the vertices, update(i) for each, with the contacts of the same
  // vertices after it; for the integrators that change x only here it first copies x to xOld.
  // Marks the cached acceleration invalid when a contact changed a velocity.
  template <class Update>
  void lastPass(Update&& update);
  bool savesOldInLastPass() const;
  // Whether the step keeps the positions at its start (xOld): for the static colliders' and the
  // bodies' contacts.
  bool keepsOld() const { return !model_->colliders.empty() || contacts_ != nullptr; }
  // Resolves the contacts of vertices [begin, end) along their paths xOld -> x; true if any
  // vertex touched a collider or a damping layer.
  bool collide(std::size_t begin, std::size_t end, Vec3* velocity);
  // The adaptive Verlet step resolves the static colliders on its candidate (xn_, vs_) before
  // evaluating the forces there, and returns the largest impact error of vertices [begin, end);
  // recordCandidateContacts books the hits once the candidate is taken.
  double collideCandidate(std::size_t begin, std::size_t end, double h);
  void recordCandidateContacts(std::size_t begin, std::size_t end);
  // Vertex i touched a static collider in the step just taken (hit) or not: its contact history.
  void bookContact(std::size_t i, bool hit);
  // How far a vertex with `velocity` that hits at `hit` is misplaced by getting its contact
  // velocity at the end of a step h instead of at the hit: |dv| (1 - s) h [m].
  double impactMisplacement(const Vec3& velocity, const ContactHit& hit, bool resting, double h) const;
  // One function per integrator: advances the state by dt_ from its time, contacts included.
  void stepExplicitEuler();
  void stepSymplecticEuler();
  void stepVelocityVerlet();
  void stepLeapfrog();
  void stepRK4();
  void stepBackwardEuler();
  void stepVbd();
  void stepBogackiShampine();
  void stepAdaptiveVerlet();
  // The adaptive steps' shared parts: the next step to try (false: none is long enough, the
  // run must stop; stepProblem() says why), and the verdict on a tried step from its embedded
  // error and its impacts' (true: accepted and taken).
  bool chooseStep(double& h, double& wanted);
  // impactGiven >= 0: the impacts' error, already estimated (collideCandidate); otherwise impactError's.
  bool judge(double h, double wanted, double embedded, bool afterRejection, double impactGiven = -1.0);
  // The adaptive step's error estimates, as fractions of the tolerance (<= 1: accepted).
  double impactError(double h) const;
  // Takes the candidate state (xn_, vn_) as the step's end, resolving the static colliders; the
  // controller's next step is factor x h.
  void accept(double h, double wanted, double factor, double error, bool afterRejection);
  // A vertex touched a static collider within the resting window (impacts are inelastic then).
  bool restingAt(std::size_t i) const;
  // The adaptive step's stability bound: kStableFraction of the step its stiffest mode allows
  // (sim/stability.h, ModeEstimator), at the current shape: Gershgorin's bound, cheap, made again
  // every few steps (and bound-steps of time) and at every stop, tracks the shape's stiffening,
  // and the mode is found again when that bound has moved by a factor 2 (or every 64 updates);
  // in between, the mode's step is scaled by the bound's change. Never below Gershgorin's own step.
  void updateStableStep();
  // Immutable once made (the colliders' trees built): on the heap, as Forces keeps its address
  // across moves of the World.
  std::unique_ptr<const Model> model_;
  Integrator integrator_;
  double dt_;
  State state_;
  bool staggered_ = false;  // the last step was symplectic Euler's (synchronizedState)
  mutable uint64_t evaluations_ = 0;
  // Scratch, sized once.
  std::vector<Vec3> xOld_, a_, k1v_, k2x_, k2v_, k3x_, k3v_, k4v_, xs_, vs_, aNext_;
  std::vector<uint16_t> sinceContact_;  // steps since each vertex last touched a collider
  int restingSteps_ = 0;                // contact within this many steps is resting contact
  bool dampingLayers_ = false;          // a plane has a damping layer (soft ground)
  bool cachedAccelerationValid_ = false;  // velocity Verlet reuses a(t + dt) as the next a(t)
  AdaptiveStep adaptive_;  // the adaptive step's controller (sim/adaptive_step.h)
  // What moves on its own: the colliders' poses over the step, the pin tracks, the landings.
  Drivers drivers_;
  const ColliderPoses* poses() const { return drivers_.poses(); }
  // Puts the tracked pins where their motion has them at the state's time (and frees those due).
  void followPins();
  std::vector<double> lastContactTime_;  // per vertex: when it last touched a static collider
  std::vector<Vec3> xn_, vn_, vBefore_;  // a step's candidate state; velocities before contact
  std::vector<uint8_t> candidateHit_;    // per vertex: the candidate touched a static collider
  std::unique_ptr<ImplicitSolver> implicit_;  // workspace of the backward Euler integrator
  std::unique_ptr<VbdSolver> vbd_;            // the vertex block descent integrator's
  std::unique_ptr<Forces> forces_;          // the force stages, their scratch and the threads
  std::unique_ptr<BodyContacts> contacts_;  // null: no contact between or within bodies
};

}  // namespace springy

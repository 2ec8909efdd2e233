// springy: the adaptive step's controller (World::adaptive(): Bogacki-Shampine 3(2) and adaptive
// Verlet), its state and its decisions apart from the integrators that take the steps.
//
// Each step's local error is estimated twice by the World: by the integrator's embedded pair
// (in positions) and, for each vertex about to hit a static collider, by the part of the step it
// would spend stopped at the surface instead of rebounding. A step whose largest error exceeds
// the tolerance times the vertex's body size is taken again, shorter; the next step follows a PI
// controller (Gustafsson; Hairer & Wanner, Solving ODEs II, IV.2) with safety factor 0.9. The
// step never exceeds kStableFraction of the stable step of the stiffest mode at the current
// shape, and lands on the stop (a frame) and on the moving colliders' keyframes.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sim/integrators.h"
#include "sim/model.h"

namespace springy {

class Forces;
class ModeEstimator;

// The adaptive integrator's step statistics (World::stepStats).
struct StepStats {
  uint64_t accepted = 0, rejected = 0;
  uint64_t contactRejected = 0;          // of the rejected: for a predicted impact's error
  double smallest = 0.0, largest = 0.0;  // accepted steps [s] (the smallest: not one shortened to land on a stop)
  uint64_t landed = 0;                   // accepted steps shortened to land on a stop
};

class AdaptiveStep {
 public:
  static constexpr double kMinStep = 1e-9;  // [s] below it the run stops (problem())
  // The step never exceeds this fraction of the stable step of its stiffest mode at the current
  // shape (updated every 4 steps and at every stop: a compressed body is stiffer). The embedded
  // estimate alone let a mode grow from round-off while it was still too small to see (the
  // hanging sphere's energy rose within 0.07 s at tolerance 1e-3).
  static constexpr double kStableFraction = 0.9;

  AdaptiveStep();
  ~AdaptiveStep();
  AdaptiveStep(AdaptiveStep&&) noexcept;
  AdaptiveStep& operator=(AdaptiveStep&&) noexcept;

  // Per vertex: 1 / (tolerance x its body's rest size), the factor the errors are judged by.
  void setTolerance(const Model& model, double tolerance);
  double tolerance() const { return tolerance_; }
  const std::vector<double>& inverseScale() const { return invScale_; }
  void setFirstStep(double h) { hNext_ = h; }
  void setStop(double time) { stop_ = time; }

  // The next step to try from time t: the controller's, under the stability bound, shortened to
  // land on the stop or the next of `kinks` (or to halve what is left before it). False when
  // none is long enough: problem() says why, and the run must stop.
  bool choose(double t, const std::vector<double>& kinks, double& h, double& wanted);
  bool landed() const { return landed_; }
  double landAt() const { return landAt_; }

  // The verdict on a tried step of h from its errors as fractions of the tolerance (embedded:
  // NaN for a candidate that is not finite, taken so that the monitor names the blow-up). True:
  // accepted, with the controller's factor for the next step; false: rejected (the next try is
  // shorter).
  bool judge(double h, double embedded, double impact, double& factor, double& error);
  // Books an accepted step (factor, error: judge's); true when the stability bound is due again.
  bool accept(double h, double wanted, double factor, double error, bool afterRejection);
  // After contact between bodies changed velocities by up to e tolerances' worth: the next step
  // short enough for that.
  void limitAfterContact(double h, double e);

  // The stability bound at positions x: Gershgorin's (sim/stability.h), made again every few
  // steps, and the stiffest mode found again when that bound has moved by a factor 2 (or every
  // 64 updates); in between, the mode's step scaled by the bound's change. Adds the force
  // evaluations the mode's search took to `evaluations`.
  void updateStableStep(const Forces& forces, const std::vector<Vec3>& x, const double* invMass, Integrator integrator,
                        uint64_t& evaluations);
  double stableStep() const { return stableStep_; }

  const StepStats& stats() const { return stats_; }
  const std::string& problem() const { return problem_; }

 private:
  double tolerance_ = 1e-4;
  double stop_ = 0.0;                 // stepToward's target (ignored when not ahead)
  double errorBefore_ = 1.0;          // the last accepted step's error (the PI controller's memory)
  double hNext_ = 0.0;                // the controller's next step [s]
  double stableStep_ = 0.0;           // its stability bound [s]
  int sinceStableUpdate_ = 0;         // accepted steps since it was made
  double sinceStableTime_ = 0.0;      // and their time [s]
  std::unique_ptr<ModeEstimator> modes_;  // the stiffest mode, found again when the bound moves
  double modeStep_ = 0.0;             // the step it allows [s]
  double boundAtMode_ = 0.0;          // Gershgorin's step when it was found [s]
  int sinceMode_ = 0;                 // bound updates since
  bool landed_ = false;               // the step in progress lands on landAt_
  double landAt_ = 0.0;               // the stop, or a moving collider's keyframe before it
  std::vector<double> invScale_;      // per vertex: 1 / (tolerance x its body's rest size)
  StepStats stats_;
  std::string problem_;
};

}  // namespace springy

#include "sim/adaptive_step.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>

#include "sim/force_stages.h"
#include "sim/stability.h"

namespace springy {

AdaptiveStep::AdaptiveStep() = default;
AdaptiveStep::~AdaptiveStep() = default;
AdaptiveStep::AdaptiveStep(AdaptiveStep&&) noexcept = default;
AdaptiveStep& AdaptiveStep::operator=(AdaptiveStep&&) noexcept = default;

void AdaptiveStep::setTolerance(const Model& model, double tolerance) {
  assert(tolerance > 0.0);
  tolerance_ = tolerance;
  invScale_.assign(model.vertexCount(), 0.0);
  for (const BodyInfo& b : model.bodies) {
    const double scale = 1.0 / (tolerance * std::max(b.restSize, 1e-9));
    std::fill(invScale_.begin() + b.firstVertex, invScale_.begin() + b.firstVertex + b.vertexCount, scale);
  }
}

bool AdaptiveStep::choose(double t, const std::vector<double>& kinks, double& h, double& wanted) {
  // The controller's step under the stability bound, shortened to land on the stop (or to halve
  // what is left, so that no sliver of a step remains before it).
  wanted = std::min(hNext_, stableStep_);
  h = wanted;
  landed_ = false;
  landAt_ = stop_;
  // A moving collider's keyframe ahead, before the stop, is landed on too (its velocity or
  // acceleration jumps there).
  const auto kink = std::upper_bound(kinks.begin(), kinks.end(), t);
  if (kink != kinks.end() && (!(stop_ > t) || *kink < stop_)) landAt_ = *kink;
  if (landAt_ > t) {
    const double left = landAt_ - t;
    if (h >= left) {
      h = left;
      landed_ = true;
    } else if (2.0 * h > left) {
      h = 0.5 * left;
    }
  }
  if (landed_ || h >= kMinStep) return true;
  char text[320];
  if (stableStep_ < kMinStep) {
    std::snprintf(text, sizeof text,
                  "at t = %.6g s the adaptive step fell below %.3g s: the stiffest mode is stable only below %.3g s; "
                  "try longer periods (a softer material) or --integrator backward_euler",
                  t, kMinStep, stableStep_ / kStableFraction);
  } else {
    std::snprintf(text, sizeof text,
                  "at t = %.6g s the adaptive step fell below %.3g s without meeting the tolerance %.3g; try a larger "
                  "--tolerance, or a fixed step (--integrator rk4 --dt ...)",
                  t, kMinStep, tolerance_);
  }
  problem_ = text;
  return false;
}

bool AdaptiveStep::judge(double h, double embedded, double impact, double& factor, double& error) {
  // A step whose candidate is not finite is taken: the monitor names the blow-up.
  if (std::isnan(embedded)) {
    factor = error = 1.0;
    return true;
  }
  if (embedded <= 1.0 && impact <= 1.0) {
    // PI controller on the embedded error (local error ~ h^3 for both pairs: exponents 0.7/3
    // and 0.4/3). The impact error grows like h^2 in sustained contact (the velocity a step
    // stops grows like h) and like h at a first impact: the square root serves both (measured:
    // with the inverse, four times as many steps were taken again).
    const double e = std::max(embedded, 1e-10);
    double f = 0.9 * std::pow(e, -0.7 / 3.0) * std::pow(errorBefore_, 0.4 / 3.0);
    if (impact > 0.0) f = std::min(f, 0.9 / std::sqrt(impact));
    factor = std::clamp(f, 0.2, 5.0);
    error = e;
    return true;
  }
  ++stats_.rejected;
  if (impact > 1.0) ++stats_.contactRejected;
  const double f = impact > 1.0 ? 0.9 / std::sqrt(impact) : 0.9 * std::pow(embedded, -1.0 / 3.0);
  hNext_ = h * std::clamp(f, 0.1, 0.9);
  return false;
}

bool AdaptiveStep::accept(double h, double wanted, double factor, double error, bool afterRejection) {
  // After a rejection the step does not grow again at once (Hairer & Wanner's rule).
  if (afterRejection) factor = std::min(factor, 1.0);
  errorBefore_ = error;
  // A step shortened to land on the stop says little about the next one's length.
  hNext_ = landed_ ? std::max(factor * h, std::min(factor, 1.0) * wanted) : factor * h;
  stats_.largest = std::max(stats_.largest, h);
  if (!landed_) {
    stats_.smallest = stats_.accepted == stats_.landed ? h : std::min(stats_.smallest, h);
  } else {
    ++stats_.landed;
  }
  ++stats_.accepted;
  // Made again at the step's end shape, after 4 steps and 4 bound-steps of time: as often as
  // every 4 steps while the steps are at the bound, less often while an impact or the tolerance
  // keeps them far below it (a shape stiffens with time, not with steps; the bound's update was
  // a third of an adaptive run).
  ++sinceStableUpdate_;
  sinceStableTime_ += h;
  const bool due = sinceStableUpdate_ >= 4 && (!std::isfinite(stableStep_) || sinceStableTime_ >= 3.99 * stableStep_);
  return landed_ || due;
}

void AdaptiveStep::limitAfterContact(double h, double e) {
  if (e > 1.0) hNext_ = std::min(hNext_, 0.9 * h / e);
}

void AdaptiveStep::updateStableStep(const Forces& forces, const std::vector<Vec3>& x, const double* invMass,
                                    Integrator integrator, uint64_t& evaluations) {
  // At the current shape: a compressed body is stiffer. The horizon only matters for methods
  // that amplify every mode, which these do not.
  constexpr int kFirstIterations = 60, kIterations = 8, kEvaluationsPerIteration = 4;
  const Integrator scheme = integrator == Integrator::AdaptiveVerlet ? Integrator::VelocityVerlet : integrator;
  const double bound = estimateStability(forces.model(), x, scheme, 1.0, invMass).dtMax;
  sinceStableUpdate_ = 0;
  sinceStableTime_ = 0.0;
  if (!std::isfinite(bound)) {
    stableStep_ = std::numeric_limits<double>::infinity();
    return;
  }
  const bool first = !modes_;
  if (first) modes_ = std::make_unique<ModeEstimator>(forces);
  if (first || bound < 0.5 * boundAtMode_ || bound > 2.0 * boundAtMode_ || ++sinceMode_ >= 64) {
    const int iterations = first ? kFirstIterations : kIterations;
    modeStep_ = ModeEstimator::step(scheme, modes_->estimate(x, iterations), 1.0);
    evaluations += static_cast<uint64_t>(kEvaluationsPerIteration * iterations);
    boundAtMode_ = bound;
    sinceMode_ = 0;
  }
  const double limit = std::max(bound, modeStep_ * (bound / boundAtMode_));
  stableStep_ = std::isfinite(limit) ? kStableFraction * limit : std::numeric_limits<double>::infinity();
}

}  // namespace springy

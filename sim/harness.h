// springy: runs under the stability monitor, and the largest stable step found by bisection:
// what the stability study (`springy study stability`), its tests and docs/stability.md
// measure the advisor (sim/stability.h) against.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim/model.h"
#include "sim/world.h"

namespace springy {

// Measurement: one run of `horizon` seconds under the stability monitor (finite, no blow-up
// beyond 10 times the rest size, energy never more than its scale above the start; checked
// every few steps and at the end).
struct RunOutcome {
  bool stable = true;
  std::string failure;   // the monitor's message when not stable
  std::string kind;      // "nan", "blow-up", "energy", "penetration", "volume" or "" when stable
  uint64_t step = 0;     // the step at which it failed
  bool finiteAtEnd = true;  // every position and velocity finite when the run stopped
};
// The energy rise a measuring run allows, as a fraction of the body's scale (the monitor's
// default is 2 %: a measuring run asks for stability, not accuracy).
constexpr double kCaseEnergyTolerance = 1.0;
// The kind of a monitor's failure message, as RunOutcome::kind.
std::string failureKind(const std::string& message);

RunOutcome runMonitored(const Model& model, Integrator integrator, double dt, double horizon,
                        const std::vector<Vec3>* initialPositions = nullptr);

// Largest stable step found by bisection (in log dt) between a stable and an unstable step
// bracketing `guess`; `failure` is what failed first just above it. dt is capped at maxDt
// (reported with capped = true when still stable there).
struct MeasuredStep {
  double dt = 0;
  bool capped = false;
  RunOutcome above;  // the run just above the limit
};
MeasuredStep largestStableStep(const Model& model, Integrator integrator, double horizon, double guess, double maxDt,
                               const std::vector<Vec3>* initialPositions = nullptr, int iterations = 10);

// The advisor's tries (`--substeps auto`, app/suggest.cpp; the stability study): an estimate's
// step count is run over the whole horizon; after a failure the count doubles (at most
// `doublings` times and up to maxCount); with `halve`, after a pass it halves (rounded up) until a
// run fails or the count is 1. Then the count chosen passed, and half of it failed (or it is 1):
// its step is within a factor 2 of the largest stable one wherever a smaller step is no less
// stable.
struct CountTry {
  int count = 0;
  std::string failure;  // what stopped the run; empty when it passed
};
struct CountSearch {
  int count = 0;                // the count chosen; 0 when every count tried failed
  std::vector<CountTry> tries;  // in the order run
};
// `run(count)` runs the whole horizon at that count: "" when it passes, else what stopped it.
CountSearch searchCount(int first, int maxCount, int doublings, bool halve, const std::function<std::string(int)>& run);

// The same tries on a case (the stability study): runs under the monitor as largestStableStep's
// at steps maxDt / n, from the first n whose step is at most `proposed`; dt = 0 when every step
// tried failed. Then `iterations` halvings (in log dt) of the bracket they leave, between the step
// given and the smallest failing step above it: `largest` (capped when maxDt itself passed).
struct TriedStep {
  double dt = 0;
  int runs = 0;  // the tries'
  MeasuredStep largest;
};
TriedStep triedStep(const Model& model, Integrator integrator, double horizon, double proposed, double maxDt,
                    const std::vector<Vec3>* initialPositions = nullptr, int iterations = 0);

}  // namespace springy

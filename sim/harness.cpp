#include "sim/harness.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/monitor.h"

namespace springy {

std::string failureKind(const std::string& m) {
  return m.find("NaN") != std::string::npos              ? "nan"
         : m.find("blew up") != std::string::npos        ? "blow-up"
         : m.find("energy") != std::string::npos         ? "energy"
         : m.find("behind a plane") != std::string::npos ? "penetration"
         : m.find("volume") != std::string::npos         ? "volume"
                                                         : "other";
}

RunOutcome runMonitored(const Model& model, Integrator integrator, double dt, double horizon,
                        const std::vector<Vec3>* initialPositions) {
  World world(model, integrator, dt);
  if (initialPositions) world.setState(*initialPositions, world.velocities());
  // Stability, not accuracy: energy may wander (a symplectic method's energy error is O(dt)),
  // but never rise by more than its own scale.
  MonitorLimits limits;
  limits.energyTolerance = kCaseEnergyTolerance;
  limits.energyFromLowest = false;
  Monitor monitor(world, limits);
  RunOutcome out;
  const auto steps = static_cast<uint64_t>(std::llround(horizon / dt));
  const uint64_t every = std::max<uint64_t>(1, std::min<uint64_t>(20, steps / 50));
  for (uint64_t s = 1; s <= steps; ++s) {
    world.step();
    if (s % every != 0 && s != steps) continue;
    if (const auto failure = monitor.check(world)) {
      out.stable = false;
      out.failure = failure->message;
      out.step = failure->step;
      out.kind = failureKind(failure->message);
      break;
    }
  }
  for (const Vec3& p : world.positions()) out.finiteAtEnd = out.finiteAtEnd && isFinite(p);
  for (const Vec3& v : world.velocities()) out.finiteAtEnd = out.finiteAtEnd && isFinite(v);
  return out;
}

namespace {

// `iterations` halvings in log dt of [lo, hi] (lo stable, hi not); the last failing run in `above`.
template <class Run>
double bisectStable(const Run& run, double lo, double hi, int iterations, RunOutcome& above) {
  for (int i = 0; i < iterations; ++i) {
    const double mid = std::sqrt(lo * hi);
    RunOutcome r = run(mid);
    if (r.stable) {
      lo = mid;
    } else {
      hi = mid;
      above = std::move(r);
    }
  }
  return lo;
}

}  // namespace

MeasuredStep largestStableStep(const Model& model, Integrator integrator, double horizon, double guess, double maxDt,
                               const std::vector<Vec3>* initialPositions, int iterations) {
  MeasuredStep out;
  auto run = [&](double dt) { return runMonitored(model, integrator, dt, horizon, initialPositions); };
  double hi = std::min(guess * 4.0, maxDt);
  RunOutcome atHi = run(hi);
  while (atHi.stable) {
    if (hi >= maxDt) {
      out.dt = maxDt;
      out.capped = true;
      return out;
    }
    hi = std::min(hi * 4.0, maxDt);
    atHi = run(hi);
  }
  double lo = hi / 4.0;
  for (RunOutcome atLo = run(lo); !atLo.stable; atLo = run(lo)) {
    hi = lo;
    atHi = std::move(atLo);
    lo /= 4.0;
    if (lo < 1e-9) {
      out.dt = 0.0;
      out.above = std::move(atHi);
      return out;
    }
  }
  out.above = std::move(atHi);
  out.dt = bisectStable(run, lo, hi, iterations, out.above);
  return out;
}

CountSearch searchCount(int first, int maxCount, int doublings, bool halve,
                        const std::function<std::string(int)>& run) {
  CountSearch out;
  const auto tryCount = [&](int n) {
    out.tries.push_back({n, run(n)});
    return out.tries.back().failure.empty();
  };
  int n = std::max(first, 1);
  if (!tryCount(n)) {
    for (int doubling = 1; doubling <= doublings && 2 * n <= maxCount; ++doubling) {
      n *= 2;
      if (tryCount(n)) {
        out.count = n;  // n / 2 failed
        return out;
      }
    }
    return out;
  }
  while (halve && n > 1 && tryCount((n + 1) / 2)) n = (n + 1) / 2;
  out.count = n;
  return out;
}

TriedStep triedStep(const Model& model, Integrator integrator, double horizon, double proposed, double maxDt,
                    const std::vector<Vec3>* initialPositions, int iterations) {
  auto run = [&](double dt) { return runMonitored(model, integrator, dt, horizon, initialPositions); };
  TriedStep out;
  MeasuredStep& m = out.largest;
  double hi = INFINITY;  // the smallest failing step above the one given
  const int first = static_cast<int>(std::min(std::ceil(maxDt / proposed), 1e9));
  const CountSearch found = searchCount(first, std::numeric_limits<int>::max() / 2, 5, true, [&](int n) {
    RunOutcome r = run(maxDt / n);
    if (r.stable) return std::string();
    if (maxDt / n < hi) hi = maxDt / n, m.above = r;
    return r.failure.empty() ? std::string("unstable") : r.failure;
  });
  out.runs = static_cast<int>(found.tries.size());
  if (found.count == 0) return out;
  const double lo = out.dt = maxDt / found.count;
  m.capped = found.count == 1;
  m.dt = m.capped ? lo : bisectStable(run, lo, hi, iterations, m.above);
  return out;
}

}  // namespace springy

#include "sim/harness.h"

#include <algorithm>
#include <cmath>

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
  for (int i = 0; i < iterations; ++i) {
    const double mid = std::sqrt(lo * hi);
    RunOutcome r = run(mid);
    if (r.stable) {
      lo = mid;
    } else {
      hi = mid;
      out.above = std::move(r);
    }
  }
  out.dt = lo;
  return out;
}

}  // namespace springy

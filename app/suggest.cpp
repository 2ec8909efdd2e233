// `springy suggest` and the time-step advice of check/render/frames: the stability advisor
// (sim/stability.h) applied to a scene.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "app/commands.h"
#include "run/advisor.h"
#include "run/load.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/harness.h"
#include "sim/interrupt.h"
#include "sim/limits.h"
#include "sim/parallel.h"
#include "sim/stability.h"
#include "sim/trajectory.h"
#include "sim/world.h"

namespace springy {
namespace {

constexpr double kSafety = 0.9;  // aim below the estimated limit

// Smallest factor f in [lo, hi] with stable(f) true, assuming stable(hi) and monotonicity.
template <class F>
double smallestStable(F stable, double lo, double hi) {
  if (stable(lo)) return lo;
  for (int i = 0; i < 60; ++i) {
    const double mid = std::sqrt(lo * hi);
    (stable(mid) ? hi : lo) = mid;
  }
  return hi;
}

// How much each body squashes through its first impact, by simulation: lowest volume over
// rest, largest flattening (1 - its extent along gravity over the rest extent), over the
// horizon, at the default step (kImpactMargin under the advisor's limit for the values given).
struct Squash {
  double lowestVolume = 1.0, flattening = 0.0;
  bool finite = true;
};

// The time by which every body has met the ground and bounced: each body's fall to the nearest
// plane under it (from its lowest vertex, with its initial velocity), plus 0.6 s; the scene's
// duration if shorter; 2 s when nothing is under any body.
double squashHorizon(const SceneDesc& scene) {
  const double g = length(scene.gravity);
  double latest = -1.0;
  for (const BodyDesc& b : scene.bodies) {
    double first = INFINITY;
    for (const PlaneCollider& p : scene.planes) {
      const Vec3 n = p.normal;
      const double a = g > 0.0 ? -dot(scene.gravity, n) : 0.0;  // acceleration toward the plane
      if (!(a > 0.0)) continue;
      double h = INFINITY;
      for (const Vec3& x : b.mesh.positions) h = std::min(h, dot(x - p.point, n));
      const double u = -dot(b.velocity, n);  // initial speed toward it
      first = std::min(first, (-u + std::sqrt(std::max(0.0, u * u + 2 * a * std::max(0.0, h)))) / a);
    }
    if (std::isfinite(first)) latest = std::max(latest, first);
  }
  return std::min(scene.duration, latest >= 0.0 ? latest + 0.6 : 2.0);
}

// Stops suggest's simulations when interrupted (sim/interrupt.h): springy exits with 128 + the
// signal's number.
void stopIfInterrupted() {
  if (interrupted()) throw Error("suggest: interrupted");
}

// `stopAtBlowUp`: stop at the first body that blows up (the others keep what was measured before);
// otherwise that body is marked and the others are measured on.
std::vector<Squash> simulateSquash(const SceneDesc& scene, double horizon, bool stopAtBlowUp) {
  Model model = buildModel(scene);
  const StabilityReport r = estimateStability(model, model.restPosition, scene.integrator, horizon);
  const int substeps = std::isfinite(r.dtMax) ? safeSubsteps(scene.dt, r.dtMax, kImpactMargin) : scene.substeps;
  const Vec3 up = length(scene.gravity) > 0.0 ? scene.gravity / -length(scene.gravity) : Vec3{0.0, 1.0, 0.0};
  const auto extent = [&](const World& w, const BodyInfo& info) {
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      const double y = dot(w.positions()[i], up);
      lo = std::min(lo, y), hi = std::max(hi, y);
    }
    return hi - lo;
  };
  World world(std::move(model), scene.integrator, scene.dt / std::max(substeps, scene.substeps));
  world.setThreads(defaultThreadCount());
  const std::size_t bodies = world.model().bodies.size();
  std::vector<Squash> out(bodies);
  std::vector<double> restExtent(bodies);
  for (std::size_t b = 0; b < bodies; ++b) restExtent[b] = extent(world, world.model().bodies[b]);
  const double every = 1.0 / 240.0;  // measured this often
  double next = every;
  std::size_t blownUp = 0;
  while (world.time() < horizon && blownUp < bodies) {
    stopIfInterrupted();  // every step
    world.step();
    if (world.time() < next) continue;
    next += every;
    for (std::size_t b = 0; b < bodies; ++b) {
      if (!out[b].finite) continue;
      const BodyInfo& info = world.model().bodies[b];
      const BodyMeasures m = measureBody(world, static_cast<uint32_t>(b));
      if (!m.finite) {
        out[b].finite = false;
        if (stopAtBlowUp) return out;
        ++blownUp;
        continue;
      }
      if (info.restVolume > 0.0) out[b].lowestVolume = std::min(out[b].lowestVolume, m.volume / info.restVolume);
      out[b].flattening = std::max(out[b].flattening, 1.0 - extent(world, info) / restExtent[b]);
    }
  }
  return out;
}

// The body's periods scaled by f (f < 1: stiffer): the body material's stretch and bend
// periods, or the element material's strut and hinge periods (direct constants by 1 / f^2).
void scalePeriods(BodyDesc& desc, const BodyInfo& info, double f) {
  if (desc.material == MaterialModel::Body) {
    desc.stretchPeriod = info.stretchPeriod * f;
    desc.bendPeriod = info.bendPeriod * f;
    return;
  }
  desc.strutPeriod *= f;
  if (desc.hingePeriod > 0.0) desc.hingePeriod *= f;
  if (desc.strutStiffness) *desc.strutStiffness /= f * f;
  if (desc.hingeStiffness) *desc.hingeStiffness /= f * f;
}

// The softest factor f of its periods in [0.1, 1] (in log, five halvings) that keeps each body of
// `soft` above `keepVolume` through the first impact, or 0 where a tenth does not keep it. The
// bodies are searched together: each trial scales every body still searched by its own factor
// and simulates the scene once, so the search costs six simulations whatever the number of bodies
// (body by body it cost six per body, each of the whole scene: 50 soft balls took 500 s).
std::vector<double> keepingFactors(const SceneDesc& scene, const Model& model, const std::vector<uint32_t>& soft,
                                   double horizon, double keepVolume) {
  const std::size_t n = soft.size();
  const auto keeps = [&](const std::vector<double>& f) {
    SceneDesc trial = scene;
    for (std::size_t i = 0; i < n; ++i) {
      if (f[i] != 1.0) scalePeriods(trial.bodies[soft[i]], model.bodies[soft[i]], f[i]);
    }
    const std::vector<Squash> t = simulateSquash(trial, horizon, false);
    std::vector<bool> kept(n);
    for (std::size_t i = 0; i < n; ++i) kept[i] = t[soft[i]].finite && t[soft[i]].lowestVolume >= keepVolume;
    return kept;
  };
  std::vector<double> lo(n, 0.1), hi(n, 1.0), mid(n);
  if (n == 0) return lo;
  const std::vector<bool> atTenth = keeps(lo);
  for (int halving = 0; halving < 5; ++halving) {
    // A body that a tenth does not keep stays as it is while the others are searched.
    for (std::size_t i = 0; i < n; ++i) mid[i] = atTenth[i] ? std::sqrt(lo[i] * hi[i]) : 1.0;
    const std::vector<bool> kept = keeps(mid);
    for (std::size_t i = 0; i < n; ++i) (kept[i] ? lo[i] : hi[i]) = mid[i];
  }
  for (std::size_t i = 0; i < n; ++i) lo[i] = atTenth[i] ? lo[i] : 0.0;
  return lo;
}

void printSquash(const SceneDesc& scene, const Model& model, double keepVolume) {
  const double horizon = squashHorizon(scene);
  const std::vector<Squash> now = simulateSquash(scene, horizon, true);
  // The bodies to search: those below keepVolume, up to the first that blew up (where it stops).
  std::vector<uint32_t> soft;
  for (uint32_t b = 0; b < model.bodies.size() && now[b].finite; ++b) {
    if (model.bodies[b].restVolume > 0.0 && now[b].lowestVolume < keepVolume) soft.push_back(b);
  }
  const std::vector<double> factors = keepingFactors(scene, model, soft, horizon, keepVolume);
  std::printf("  shape through the first impact (simulated to %.3g s at the default step; --keep-volume %g):\n", horizon,
              keepVolume);
  for (uint32_t b = 0, searched = 0; b < model.bodies.size(); ++b) {
    const BodyInfo& info = model.bodies[b];
    const Squash& s = now[b];
    if (!s.finite) {
      std::printf("    body '%s': the simulation blew up; make the step smaller first\n", info.name.c_str());
      return;
    }
    if (!(info.restVolume > 0.0)) {
      std::printf("    body '%s': encloses no volume; flattened by up to %.0f%%\n", info.name.c_str(),
                  100 * s.flattening);
      continue;
    }
    std::printf("    body '%s': lowest volume %.0f%% of rest, flattened by up to %.0f%%", info.name.c_str(),
                100 * s.lowestVolume, 100 * s.flattening);
    if (s.lowestVolume >= keepVolume) {
      std::printf(": holds its shape\n");
      continue;
    }
    const double f = factors[searched++];
    if (f == 0.0) {
      std::printf(": below %.0f%%, and periods a tenth as long do not keep it either (a gas, volume_period, "
                  "holds a volume at any softness)\n",
                  100 * keepVolume);
      continue;
    }
    BodyDesc stiffer = scene.bodies[b];
    scalePeriods(stiffer, info, f);
    if (stiffer.material == MaterialModel::Body) {
      std::printf(": to keep %.0f%%: stretch_period = %.3g, bend_period = %.3g (x %.2f)\n", 100 * keepVolume,
                  *stiffer.stretchPeriod, *stiffer.bendPeriod, f);
    } else {
      std::printf(": to keep %.0f%%: its periods x %.2f (strut_period = %.3g, hinge_period = %.3g)\n",
                  100 * keepVolume, f, stiffer.strutPeriod, stiffer.hingePeriod);
    }
  }
}

// A body's stability limit as its time constants are scaled: the advisor's bound on its springs
// (sim/stability.h) for the integrator that limits it, over the scene's duration.
struct BodyLimit {
  const std::vector<RowBound>& rows;
  Integrator limiting;
  double duration;

  // The largest stable step with the body's parameters scaled by `s`.
  double dtMax(const ParameterScale& s) const { return bodyStability(rows, limiting, duration, s).dtMax; }
};

// Every time constant times f, and the strut period, strut decay, hinge period, hinge decay and
// volume period times sp, sd, hp, hd and vp besides: a stiffness goes as 1 / T^2, a damping as 1 / T.
ParameterScale scaled(double f, double sp, double sd, double hp, double hd, double vp = 1) {
  return ParameterScale{1.0 / (f * f * sp * sp), 1.0 / (f * sd), 1.0 / (f * f * hp * hp), 1.0 / (f * hd),
                        1.0 / (f * f * vp * vp)};
}

// "KEY = VALUE" for a suggested period or decay, or for the direct constant where the scene gives
// one instead (scaled by directScale); a key ending in '=' (">=", "<=") takes no second one.
std::string valueText(const char* periodKey, double period, const std::optional<double>& direct, const char* directKey,
                      double directScale) {
  std::ostringstream s;
  const std::string key = direct ? directKey : periodKey;
  s << key << (key.back() == '=' ? " " : " = ") << (direct ? *direct * directScale : period);
  return s.str();
}

// The body material's advice: its struts follow stretch_period, its hinges bend_period; its
// deformation damping (a rate per vertex, like drag) barely moves the limit.
void printBodyMaterialAdvice(const BodyLimit& limit, const BodyInfo& info, double h) {
  const bool hinges = info.hingeCount > 0;
  const double bodyTarget = h / kSafety;
  auto stable = [&](double sp, double bp) { return limit.dtMax(scaled(1, sp, 1, bp, 1)) >= bodyTarget; };
  double fb = 1.0;
  if (!stable(1.0, 1.0)) {
    double hi = 2.0;
    while (!stable(hi, hi) && hi < 1e6) hi *= 2;
    fb = smallestStable([&](double x) { return stable(x, x); }, hi / 2, hi);
  }
  if (fb > 1.0) {
    std::printf("    suggested for a step of %g s: stretch_period = %.4g, bend_period = %.4g (x %.3g)\n", h,
                info.stretchPeriod * fb, info.bendPeriod * fb, fb);
  }
  const double gs = smallestStable([&](double g) { return stable(g * fb, fb); }, 1e-4, 1.0);
  const double gb = hinges ? smallestStable([&](double g) { return stable(fb, g * fb); }, 1e-4, 1.0) : 1.0;
  std::printf("    stiffest stable values at a step of %g s, one at a time: stretch_period >= %.4g", h,
              info.stretchPeriod * fb * gs);
  if (hinges) std::printf(", bend_period >= %.4g", info.bendPeriod * fb * gb);
  std::printf("\n");
}

// The uniform scale f >= 1 of every time constant that makes the limit reach `target`: the limit
// scales with f for the horizon-independent methods; bisect anyway (explicit Euler's depends on
// the horizon).
double uniformScale(const BodyLimit& limit, double target) {
  if (limit.dtMax(scaled(1, 1, 1, 1, 1)) >= target) return 1.0;
  double hi = 2.0;
  while (!(limit.dtMax(scaled(hi, 1, 1, 1, 1)) >= target) && hi < 1e6) hi *= 2;
  return smallestStable([&](double x) { return limit.dtMax(scaled(x, 1, 1, 1, 1)) >= target; }, hi / 2, hi);
}

// The factor in [1e-4, 1] of the stiffest stable value of one parameter alone (0 strut period,
// 1 strut decay, 2 hinge period, 3 hinge decay, 4 volume period), the others at f times their value.
double stiffestAlone(const BodyLimit& limit, double f, double target, int which) {
  return smallestStable(
      [&](double g) {
        const double sp = which == 0 ? g : 1, sd = which == 1 ? g : 1, hp = which == 2 ? g : 1, hd = which == 3 ? g : 1,
                     vp = which == 4 ? g : 1;
        return limit.dtMax(scaled(f, sp, sd, hp, hd, vp)) >= target;
      },
      1e-4, 1.0);
}

// The element material's values with every time constant times f.
void printScaledValues(const BodyDesc& desc, double f, bool hinges, bool gas) {
  std::printf(
      "      all time constants x %.3g: %s, %s", f,
      valueText("strut_period", desc.strutPeriod * f, desc.strutStiffness, "strut_stiffness", 1 / (f * f)).c_str(),
      valueText("strut_decay", desc.strutDecay * f, desc.strutDamping, "strut_damping", 1 / f).c_str());
  if (hinges) {
    std::printf(
        ", %s, %s",
        valueText("hinge_period", desc.hingePeriod * f, desc.hingeStiffness, "hinge_stiffness", 1 / (f * f)).c_str(),
        valueText("hinge_decay", desc.hingeDecay * f, desc.hingeDamping, "hinge_damping", 1 / f).c_str());
  }
  if (gas) std::printf(", volume_period = %g", desc.volumePeriod * f);
  std::printf("\n");
}

// The element material's stiffest stable value of each parameter alone, the others at f times their value.
void printStiffestValues(const BodyLimit& limit, const BodyDesc& desc, double f, double target, bool hinges, bool gas) {
  const double gp = stiffestAlone(limit, f, target, 0), gd = stiffestAlone(limit, f, target, 1);
  std::printf("      stiffest stable values, one at a time: %s%s, %s%s", gp <= 1e-4 ? "any " : "",
              valueText("strut_period >=", desc.strutPeriod * f * gp, desc.strutStiffness, "strut_stiffness <=",
                        1 / (f * f * gp * gp)).c_str(),
              gd <= 1e-4 ? "any " : "",
              valueText("strut_decay >=", desc.strutDecay * f * gd, desc.strutDamping, "strut_damping <=", 1 / (f * gd))
                  .c_str());
  if (hinges) {
    const double hp = stiffestAlone(limit, f, target, 2), hd = stiffestAlone(limit, f, target, 3);
    std::printf(", %s%s, %s%s", hp <= 1e-4 ? "any " : "",
                valueText("hinge_period >=", desc.hingePeriod * f * hp, desc.hingeStiffness, "hinge_stiffness <=",
                          1 / (f * f * hp * hp)).c_str(),
                hd <= 1e-4 ? "any " : "",
                valueText("hinge_decay >=", desc.hingeDecay * f * hd, desc.hingeDamping, "hinge_damping <=",
                          1 / (f * hd)).c_str());
  }
  if (gas) {
    const double vp = stiffestAlone(limit, f, target, 4);
    std::printf(", %svolume_period >= %g", vp <= 1e-4 ? "any " : "", desc.volumePeriod * f * vp);
  }
  std::printf("\n");
}

// The element material's advice: every time constant scaled to make the step stable, and the
// stiffest value of each parameter alone.
void printElementAdvice(const BodyLimit& limit, const BodyInfo& info, const BodyDesc& desc, double h) {
  const bool hinges = info.hingeCount > 0, gas = info.gasPressure > 0.0;
  const double target = h / kSafety;
  const double f = uniformScale(limit, target);
  std::printf("    suggested for a step of %g s%s:\n", h,
              f > 1.0 ? "" : " (the current values are stable; the stiffest values follow)");
  if (f > 1.0) printScaledValues(desc, f, hinges, gas);
  printStiffestValues(limit, desc, f, target, hinges, gas);
}

// Prints body `bi`'s stability: its bounds, the largest stable step, and the values that make
// the scene's step `h` stable.
void adviseBody(const SceneDesc& scene, const Model& model, uint32_t bi, double h) {
  const BodyInfo& info = model.bodies[bi];
  const BodyDesc& desc = scene.bodies[bi];
  const std::vector<RowBound> rows = gershgorinRows(model, model.restPosition.data(), bi);
  const BodyLimit limit{rows, contactLimitedIntegrator(model, bi, scene.integrator), scene.duration};
  const BodyStability now = bodyStability(rows, limit.limiting, scene.duration);
  std::printf("  body '%s' (%u vertices, %u struts, %u hinges%s)\n", info.name.c_str(), info.vertexCount,
              info.strutCount, info.hingeCount, info.gasPressure > 0.0 ? ", gas" : "");
  std::printf("    omega_max <= %.4g rad/s (2/omega_max = %.4g s), damping rate <= %.4g 1/s\n", now.omegaMax,
              now.omegaMax > 0 ? 2.0 / now.omegaMax : INFINITY, now.gammaMax);
  if (!std::isfinite(now.dtMax)) {
    std::printf("    %s is unconditionally stable on these springs: any dt and parameters\n",
                std::string(integratorName(scene.integrator)).c_str());
    return;
  }
  if (limit.limiting != scene.integrator) {
    std::printf("    %s is stable at any step on these springs, but %s (sim/stability.h)\n",
                std::string(integratorName(scene.integrator)).c_str(), kContactLimitReason);
  }
  const int substeps = safeSubsteps(scene.dt, now.dtMax, kSafety);
  std::printf("    largest stable step with the current values: %.4g s -> %s (use dt <= %.4g s, or --substeps %d "
              "with dt %g s)\n",
              now.dtMax, h <= now.dtMax ? "the current step is stable" : "the current step is UNSTABLE",
              kSafety * now.dtMax, substeps, scene.dt);
  if (desc.material == MaterialModel::Body) {
    printBodyMaterialAdvice(limit, info, h);
  } else {
    printElementAdvice(limit, info, desc, h);
  }
}

}  // namespace

int runSuggest(const SuggestOptions& options) {
  int failures = 0;
  for (const std::string& path : options.scenes) {
    SceneDesc scene;
    try {
      scene = loadSceneWith(path, options.run, false);
    } catch (const Error& e) {
      std::cerr << "springy suggest: " << e.what() << "\n";
      ++failures;
      continue;
    }
    const double h = stepSize(scene);
    const Model model = buildModel(scene);
    std::printf("%s: %s, integrator %s, dt %g s, %s (step %g s), horizon %g s\n", path.c_str(), scene.name.c_str(),
                std::string(integratorName(scene.integrator)).c_str(), scene.dt, substepsText(scene.substeps).c_str(),
                h, scene.duration);
    for (uint32_t bi = 0; bi < model.bodies.size(); ++bi) {
      stopIfInterrupted();
      adviseBody(scene, model, bi, h);
    }
    printSquash(scene, model, options.keepVolume);
  }
  return failures == 0 ? 0 : 1;
}

}  // namespace springy

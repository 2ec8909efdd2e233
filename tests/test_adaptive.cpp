// The adaptive integrator (bs32: Bogacki-Shampine 3(2) with a PI controller, `--tolerance`):
// its error follows the tolerance, it lands on every stop, it shortens its step at an impact
// and lengthens it in flight, its step sequence is the same on any thread count, and through
// contact it reaches the fixed-step schemes' error for no more work.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "scene/scene.h"
#include "sim/cases.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/monitor.h"
#include "sim/stability.h"
#include "sim/trajectory.h"

namespace springy {
namespace {

std::string scenePath(const std::string& name) { return std::string(SPRINGY_SOURCE_DIR) + "/scenes/" + name + ".toml"; }

// One mass on a damped spring pinned at its other end, released stretched: u'' = -k/m u - d/m u',
// u(0) = u0, u'(0) = 0, so u(t) = u0 e^(-g t) (cos(w t) + g/w sin(w t)), g = d/2m, w^2 = k/m - g^2.
struct Oscillator {
  static constexpr double kMass = 1.0, kLength = 1.0, kStretch = 0.1, kDamping = 0.5;
  static double stiffness() { return std::pow(2.0 * M_PI / 0.5, 2.0); }  // a period of 0.5 s
  static Model model() {
    Model m = strutModel(kMass, kMass, kLength, stiffness(), kDamping, true);
    m.bodies[0].restSize = kLength;
    m.restPosition[1].x = kLength + kStretch;
    return m;
  }
  static double exact(double t) {
    const double g = kDamping / (2.0 * kMass), w = std::sqrt(stiffness() / kMass - g * g);
    return kLength + kStretch * std::exp(-g * t) * (std::cos(w * t) + g / w * std::sin(w * t));
  }
};

// Runs the oscillator to `end` through stops every `frame` seconds; returns |x - exact| / length.
double oscillatorError(double tolerance, double end, World* out = nullptr,
                       Integrator integrator = Integrator::BogackiShampine) {
  World world(Oscillator::model(), integrator, 1e-3);
  world.setTolerance(tolerance);
  for (int f = 1; f <= static_cast<int>(std::lround(end / 0.1)); ++f) {
    const double stop = 0.1 * f;
    while (!world.reached(stop)) world.stepToward(stop);
    EXPECT_EQ(world.time(), stop) << "the adaptive step lands on every stop exactly";
  }
  const double error = std::fabs(world.positions()[1].x - Oscillator::exact(end)) / Oscillator::kLength;
  if (out) *out = std::move(world);
  return error;
}

// The tolerance bounds each step's local error; over 2 s (four periods, a few hundred steps) the
// errors add up to a bounded multiple of it, which falls with it: at most 30, 60 and 100 times
// the tolerance at 1e-4, 1e-6 and 1e-8, and at least `fall` times smaller per hundredfold.
void expectErrorFollowsTolerance(Integrator integrator, double fall) {
  const auto error = [&](double tolerance) { return oscillatorError(tolerance, 2.0, nullptr, integrator); };
  const double coarse = error(1e-4), middle = error(1e-6), fine = error(1e-8);
  EXPECT_LT(coarse, 30 * 1e-4);
  EXPECT_LT(middle, 60 * 1e-6);
  EXPECT_LT(fine, 100 * 1e-8);
  EXPECT_LT(middle, coarse / fall);
  EXPECT_LT(fine, middle / fall);
}

TEST(Adaptive, ErrorOnADampedOscillatorFollowsTheTolerance) {
  // Measured: tolerance 1e-4 -> 1.1e-3, 1e-6 -> 2.8e-5, 1e-8 -> 4.1e-7 (11, 28 and 41 times the
  // tolerance: the finer tolerances take more steps, whose local errors add).
  expectErrorFollowsTolerance(Integrator::BogackiShampine, 20.0);
}

TEST(Adaptive, VerletErrorOnADampedOscillatorFollowsTheTolerance) {
  // verlet_adaptive, whose estimate h^2/6 |a1 - a0| is of its local position error. Measured:
  // 1e-4 -> 6.7e-4, 1e-6 -> 3.1e-5, 1e-8 -> 8.0e-7 (a second-order method takes more steps for
  // the same tolerance, so its local errors add up more: factors 21 and 39 per hundredfold,
  // against the third-order pair's 40 and 69).
  expectErrorFollowsTolerance(Integrator::AdaptiveVerlet, 15.0);
}

TEST(Adaptive, TakesLongerStepsForALooserTolerance) {
  World loose(Oscillator::model(), Integrator::BogackiShampine, 1e-3);
  World tight(Oscillator::model(), Integrator::BogackiShampine, 1e-3);
  oscillatorError(1e-3, 2.0, &loose);
  oscillatorError(1e-7, 2.0, &tight);
  // Steps scale like tolerance^(1/3) for a third-order method: 10^4 in tolerance, about 21 in steps.
  const double ratio = static_cast<double>(tight.stepCount()) / static_cast<double>(loose.stepCount());
  EXPECT_GT(ratio, 8.0);
  EXPECT_LT(ratio, 50.0);
}

// The bunny (scenes/bunny.toml) with RK4 at 3.5 ms, one substep, frame by frame under the
// monitor for half a second; the monitor's records at the end.
struct BunnyRun {
  std::optional<Failure> failure;
  BodyRecord record;
};
BunnyRun runBunny(double dt) {
  const SceneDesc scene = loadScene(scenePath("bunny"));
  World world(buildModel(scene), Integrator::RK4, dt);
  Monitor monitor(world);
  BunnyRun run;
  for (int f = 1; f <= 15 && !run.failure; ++f) {
    while (!world.reached(f / 30.0)) world.stepToward(f / 30.0);
    run.failure = monitor.check(world);
  }
  run.record = monitor.records()[0];
  return run;
}

TEST(Monitor, CatchesAnInstabilityThatSaturatesUnderTheFallsTolerance) {
  // The bunny's stiffest mode allows RK4 2.53 ms (ModeEstimator). At 3.5 ms the instability
  // grows while the bunny falls and saturates at some 20 J, pumping balanced by damping and drag
  // (docs/stability.md): under 2 % of the energy scale that counts its 10 m fall (1206 J), so a
  // rise measured against the start's scale never fails it, and it rests jittering for good. Its
  // energy left to spend at its lowest is its centroid's height above the ground (786 J): against
  // that the rise fails within a fifth of a second.
  const BunnyRun fast = runBunny(0.0035);
  ASSERT_TRUE(fast.failure.has_value());
  EXPECT_NE(fast.failure->message.find("total energy rose"), std::string::npos) << fast.failure->message;
  EXPECT_LT(fast.failure->time, 0.2);
  const BodyRecord& r = fast.record;
  EXPECT_LT(r.last.total() - r.lowestTotal, 0.02 * r.energyScale);  // the start's scale: passes
  EXPECT_GT(r.last.total() - r.lowestTotal, 0.02 * r.lowestSpendable);
  // The stable step, on the same measure, passes.
  const BunnyRun stable = runBunny(0.0025);
  EXPECT_FALSE(stable.failure.has_value()) << stable.failure->message;
}

TEST(Monitor, ALandingsStepBoundsWhereTheCubeStartsToGainEnergy) {
  // The cube (scenes/cube.toml: 8 vertices, soft springs whose own limit is some 0.1 s,
  // restitution 1) lands at 17 m/s. A vertex put back on the ground after sinking up to v h
  // behind it gains m g v h, and nothing dissipates it: landingStep is the step at which the
  // deepest sink adds the monitor's 2 % of what the body has to spend. Below it every run passes;
  // just above it (where a landing's phase sinks the vertices deep enough) runs fail.
  const SceneDesc scene = loadScene(scenePath("cube"));
  const Model model = buildModel(scene);
  const World start(model, scene.integrator, scene.dt);
  const double landing = landingStep(start, 0, MonitorLimits{}.energyTolerance);
  EXPECT_NEAR(landing, 0.0233, 0.0005);  // 0.02 * 1570 J / (8 kg * 9.81 m/s^2 * 17.2 m/s)
  {
    // A bounce that keeps 0.6 of the speed takes (1 - 0.36) m v^2 / 2 in the landing's step,
    // which covers the gain up to (1 - 0.36) v / 2g = 0.56 s more.
    Model softer = model;
    for (PlaneCollider& p : softer.colliders.planes) p.material.restitution = 0.6;
    const World world(softer, scene.integrator, scene.dt);
    EXPECT_NEAR(landingStep(world, 0, MonitorLimits{}.energyTolerance) - landing, 0.64 * 17.16 / (2 * 9.81), 0.01);
  }
  const auto run = [&](double h) {
    PathSettings s;
    s.integrator = scene.integrator;
    s.dt = h;
    s.duration = scene.duration;
    return tracePath(model, s);
  };
  for (double f : {0.5, 0.75, 0.95}) EXPECT_TRUE(run(f * landing).complete) << f << " of the landing's step";
  int failed = 0;
  for (int k = 0; k <= 10; ++k) {
    const RunPath r = run((1.0 + 0.05 * k) * landing);
    if (!r.complete) {
      ++failed;
      EXPECT_NE(r.failure.find("total energy rose"), std::string::npos) << r.failure;
    }
  }
  EXPECT_GE(failed, 1);
  // The survey behind --substeps auto takes it: the mode's own limit is 4-5 times larger.
  const StabilitySurvey survey = surveyStability(model, scene.integrator, scene.duration, 1.0 / 30, scene.dt, 1e-4);
  EXPECT_TRUE(survey.landing);
  EXPECT_LE(survey.dtMax, landing);
  EXPECT_GT(survey.atRest, 4 * landing);
}

TEST(Monitor, ASymplecticSwingOfWhatIsLeftIsNoRise) {
  // The stiff strut (P = 1 ms, T = 0.1 s, no gravity) with the default adaptive Verlet: once
  // damping has spent most of its energy the tolerance no longer limits the step, which grows to
  // the stability cap (omega h near 1.8), where Verlet's energy read at an instant swings by up to
  // 5 times the mode's. From its lowest (0.58 J at 0.108 s) it reads 1.54 J at 0.112 s: bounded,
  // a swing, not a rise; measured against what was left (0.012 J allowed) it stopped the run. The
  // symplectic methods keep the start's scale (energySwings).
  const StabilityCase c = strutCase(1e-3, 0.1);
  World world(c.model, kDefaultAdaptive, 1e-4);
  world.setTolerance(1e-4);
  world.setState(c.positions, world.velocities());
  Monitor monitor(world);
  for (int f = 1; f <= 50; ++f) {
    while (!world.reached(f * 0.004)) world.stepToward(f * 0.004);
    const std::optional<Failure> failure = monitor.check(world);
    ASSERT_FALSE(failure.has_value()) << failure->message;
  }
  EXPECT_TRUE(energySwings(kDefaultAdaptive));
  EXPECT_FALSE(energySwings(Integrator::RK4));
}

// A scene run with the adaptive step, frame by frame under the monitor.
World runScene(const std::string& name, double tolerance, double duration, unsigned threads,
               std::vector<std::pair<double, double>>* steps = nullptr,
               Integrator integrator = Integrator::BogackiShampine) {
  const SceneDesc scene = loadScene(scenePath(name));
  World world(buildModel(scene), integrator, stepSize(scene));
  world.setTolerance(tolerance);
  world.setThreads(threads, 1);  // split even a small model, so that the threads really share it
  Monitor monitor(world);
  const double frame = 1.0 / 30.0;
  for (int f = 1; f <= static_cast<int>(std::lround(duration / frame)); ++f) {
    const double stop = f * frame;
    while (!world.reached(stop)) {
      const double before = world.time();
      world.stepToward(stop);
      // Steps that end on a frame were shortened to land there: not the controller's choice.
      if (steps && world.time() != stop) steps->push_back({before, world.dt()});
    }
    const auto failure = monitor.check(world);
    EXPECT_FALSE(failure) << name << ": " << failure->message;
    if (failure) break;
  }
  EXPECT_TRUE(world.stepProblem().empty()) << world.stepProblem();
  return world;
}

TEST(Adaptive, ShortensTheStepAtAnImpactAndLengthensItInFlight) {
  // The single sphere falls 14 m and lands at about 1.7 s (radius 6 m, released at 20 m).
  std::vector<std::pair<double, double>> steps;
  const World world = runScene("single_sphere", 1e-4, 3.0, 1, &steps);
  const auto smallest =
      *std::min_element(steps.begin(), steps.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  EXPECT_GT(smallest.first, 1.6) << "the smallest step is taken at the landing";
  EXPECT_LT(smallest.first, 2.2);
  std::vector<double> flight;
  for (const auto& [t, dt] : steps) {
    if (t < 1.5) flight.push_back(dt);
  }
  std::sort(flight.begin(), flight.end());
  const double typicalFlight = flight[flight.size() / 2];
  EXPECT_LT(smallest.second, typicalFlight / 5.0);
  // In flight the step is at the stability bound: 0.9 of the step the stiffest mode allows
  // (ModeEstimator, sim/stability.h; the shape in free fall is the rest shape), not the scene's 2 ms,
  // and well above Gershgorin's looser bound (damping 1382 1/s bounded, 392 1/s found).
  ModeEstimator modes(world.forces());
  const double bound = World::kStableFraction * ModeEstimator::step(Integrator::BogackiShampine,
                                                                     modes.estimate(world.model().restPosition, 60), 1.0);
  const double gershgorin =
      estimateStability(world.model(), world.model().restPosition, Integrator::BogackiShampine, 1.0).dtMax;
  EXPECT_GT(typicalFlight, 0.8 * bound);
  EXPECT_LE(typicalFlight, bound * (1.0 + 1e-12));
  EXPECT_GT(typicalFlight, 2.0 * gershgorin);
  EXPECT_GT(world.stepStats().rejected, 0u) << "an impact's first try is too long";
}

TEST(Adaptive, StepSequenceIsBitIdenticalAcrossRunsAndThreadCounts) {
  // Plane contacts (spheres) and contact between bodies (head_on): every decision of the
  // controller is a maximum over vertices, which no split of the vertices changes.
  // The spheres land at 1.7 s; head_on's balls meet at 0.375 s.
  // verlet_adaptive keeps its acceleration across steps (and drops it at a contact): spheres too.
  struct Case {
    const char* name;
    double duration;
    Integrator integrator;
  };
  for (const auto& [name, duration, integrator] :
       {Case{"spheres", 2.0, Integrator::BogackiShampine}, Case{"head_on", 0.5, Integrator::BogackiShampine},
        Case{"spheres", 2.0, Integrator::AdaptiveVerlet}}) {
    const World one = runScene(name, 1e-4, duration, 1, nullptr, integrator);
    const World again = runScene(name, 1e-4, duration, 1, nullptr, integrator);
    const World three = runScene(name, 1e-4, duration, 3, nullptr, integrator);
    if (std::string(name) == "spheres") {
      EXPECT_GT(one.stepStats().rejected, 0u) << "the comparison includes rejected steps";
    } else {
      ASSERT_NE(one.bodyContacts(), nullptr);
      EXPECT_GT(one.bodyContacts()->sinceStart().impulses, 0u) << "the balls met";
    }
    for (const World* w : {&again, &three}) {
      EXPECT_EQ(stateHash(*w), stateHash(one)) << name;
      EXPECT_EQ(w->stepCount(), one.stepCount()) << name;
      EXPECT_EQ(w->stepStats().rejected, one.stepStats().rejected) << name;
      EXPECT_EQ(w->stepStats().smallest, one.stepStats().smallest) << name;
      EXPECT_EQ(w->forceEvaluations(), one.forceEvaluations()) << name;
    }
  }
}

TEST(Adaptive, AModeNoStepAboveANanosecondCanHoldStopsWithAMessage) {
  // 1e15 N/m on 1 ug: omega = 1e12 rad/s, stable only below about 2e-12 s. Rather than crawl
  // through 1e12 steps a second, the run stops and says why and what to try.
  Model model = strutModel(1e-9, 1e-9, 1.0, 1e15, 0.0, true);
  model.bodies[0].restSize = 1.0;
  model.restPosition[1].x = 1.01;
  World world(model, Integrator::BogackiShampine, 1e-3);
  world.stepToward(1.0);
  ASSERT_FALSE(world.stepProblem().empty());
  EXPECT_EQ(world.time(), 0.0) << "no step taken";
  EXPECT_NE(world.stepProblem().find("stable only below"), std::string::npos) << world.stepProblem();
  EXPECT_NE(world.stepProblem().find("backward_euler"), std::string::npos) << world.stepProblem();
}

TEST(Adaptive, ASceneTolerancePicksTheAdaptiveStepAndABadOneIsNamed) {
  const std::string body = "\n[[body]]\nshape = \"icosphere\"\nsubdivisions = 1\n";
  const SceneDesc plain = parseScene("[scene]\ntolerance = 1e-3\n" + body, "t.toml");
  EXPECT_EQ(plain.integrator, kDefaultAdaptive);
  EXPECT_EQ(plain.tolerance, 1e-3);
  const SceneDesc chosen = parseScene("[scene]\nintegrator = \"bs32\"\ntolerance = 1e-5\n" + body, "t.toml");
  EXPECT_EQ(chosen.integrator, Integrator::BogackiShampine);
  try {
    parseScene("[scene]\ntolerance = 0.0\n" + body, "t.toml");
    FAIL() << "a zero tolerance was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("t.toml:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("tolerance"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace springy

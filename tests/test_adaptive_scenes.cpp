// The adaptive step on whole scenes (slow: full-length runs): it passes every showcase scene at
// its default tolerance, and through contact it reaches the fixed-step schemes' error for no
// more work (docs/accuracy-contact.md has the same comparison in wall time).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "scene/scene.h"
#include "sim/monitor.h"
#include "sim/trajectory.h"

namespace springy {
namespace {

std::string scenePath(const std::string& name) { return std::string(SPRINGY_SOURCE_DIR) + "/scenes/" + name + ".toml"; }

class ShowcaseScene : public testing::TestWithParam<const char*> {};

TEST_P(ShowcaseScene, PassesAtFullLengthWithTheAdaptiveStep) {
  // As `springy check SCENE --tolerance 1e-4` runs it (the default adaptive integrator): under the monitor at every
  // frame, with no step given (the scenes' own steps and substeps are what the adaptive step replaces).
  const SceneDesc scene = loadScene(scenePath(GetParam()));
  PathSettings s;
  s.integrator = kDefaultAdaptive;
  s.dt = scene.dt;
  s.tolerance = SimulationDesc{}.tolerance;
  s.frame = 1.0 / scene.view.render.fps;
  s.duration = scene.duration;
  s.threads = 2;
  const RunPath path = tracePath(buildModel(scene), s);
  EXPECT_TRUE(path.complete) << GetParam() << ": " << path.failure;
  EXPECT_NEAR(path.times.back(), scene.duration, 1e-9);
}

// A scene with contact, its first seconds, a tolerance, and the reference's step as a fraction of
// the ladder's coarsest (the reference must be converged far below the error it measures).
struct Contest {
  const char* scene;
  double duration;    // [s]
  double tolerance;   // the adaptive step's
  int referenceSplit; // reference: RK4 at the frame / (n0 * referenceSplit); its check at half that
};

class WorkPrecision : public testing::TestWithParam<Contest> {};

TEST_P(WorkPrecision, TheAdaptiveStepSitsOnOrBelowTheFixedStepsThroughContact) {
  // Against a fine RK4 reference, no run of the fixed-step ladder (symplectic Euler, Verlet,
  // leapfrog, RK4 at the frame / 17, 34, 68: 2 ms to 0.5 ms) is both more accurate than the
  // adaptive step and cheaper in force evaluations. (Wall time, which also counts the adaptive
  // step's impact and stability checks: docs/accuracy-contact.md.) All three at the default
  // tolerance 1e-4. (Before Verlet resolved the ground ahead of its force evaluation, symplectic
  // Euler at 1 ms beat it through the spheres' landings, which were then held to 1e-5.) The jelly's
  // errors are too close to its reference's own to rank.
  const Contest& c = GetParam();
  const SceneDesc scene = loadScene(scenePath(c.scene));
  const Model model = buildModel(scene);
  PathSettings s;
  s.frame = 1.0 / scene.view.render.fps;
  s.duration = c.duration;
  s.tolerance = c.tolerance;
  const double n0 = std::ceil(s.frame / 0.002);
  const auto run = [&](Integrator integrator, double dt) {
    PathSettings r = s;
    r.integrator = integrator;
    r.dt = dt;
    return tracePath(model, r);
  };
  const RunPath reference = run(Integrator::RK4, s.frame / (n0 * c.referenceSplit));
  const RunPath check = run(Integrator::RK4, s.frame / (n0 * c.referenceSplit / 2));
  const RunPath adaptive = run(kDefaultAdaptive, s.frame / n0);
  ASSERT_TRUE(reference.complete && check.complete && adaptive.complete);
  const double error = pathError(model, reference, adaptive).centroidRms;
  const double referenceError = pathError(model, reference, check).centroidRms;
  std::printf("%s: adaptive %.3g with %llu evaluations; reference check %.3g\n", c.scene, error,
              static_cast<unsigned long long>(adaptive.evaluations), referenceError);
  EXPECT_LT(referenceError, error / 4) << "the reference is converged";
  for (Integrator integrator :
       {Integrator::SymplecticEuler, Integrator::VelocityVerlet, Integrator::Leapfrog, Integrator::RK4}) {
    for (double n : {n0, 2 * n0, 4 * n0}) {
      const RunPath fixed = run(integrator, s.frame / n);
      if (!fixed.complete) continue;  // unstable at that step: no point on the curve
      const double fixedError = pathError(model, reference, fixed).centroidRms;
      EXPECT_FALSE(fixedError < error && fixed.evaluations <= adaptive.evaluations)
          << integratorName(integrator) << " at dt " << s.frame / n << " reaches " << fixedError << " with "
          << fixed.evaluations << " force evaluations; the adaptive step " << error << " with "
          << adaptive.evaluations;
    }
  }
}

// The cube lands and tumbles, the ball rolls down the ramp, the three spheres land on the ground
// and on each other. The ramp's reference converges slowly through the rolling contact (RK4 at
// the frame / (17 x 32) and / (17 x 16) differ by 4.8e-5), hence the finer one: its check differs
// by 3.7e-5, against the adaptive step's 2.9e-4 (the test prints both).
INSTANTIATE_TEST_SUITE_P(Scenes, WorkPrecision,
                         testing::Values(Contest{"cube", 4.0, 1e-4, 32}, Contest{"ramp", 4.0, 1e-4, 64},
                                         Contest{"spheres", 2.5, 1e-4, 128}),
                         [](const testing::TestParamInfo<Contest>& p) { return std::string(p.param.scene); });

INSTANTIATE_TEST_SUITE_P(Scenes, ShowcaseScene,
                         testing::Values("single_sphere", "spheres", "fixed_single_sphere", "cube", "ramp", "jelly",
                                         "bunny", "bunny_light"));

}  // namespace
}  // namespace springy

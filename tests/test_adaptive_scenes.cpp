// The adaptive step on whole scenes (slow: full-length runs): it passes every showcase scene at
// its default tolerance, and through contact it reaches the fixed-step schemes' error for no
// more work (docs/accuracy-contact.md has the same comparison in wall time).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "scene/scene.h"
#include "sim/monitor.h"
#include "sim/trajectory.h"

namespace springy {
namespace {

std::string scenePath(const std::string& name) { return std::string(SPRINGY_SOURCE_DIR) + "/scenes/" + name + ".toml"; }

class ShowcaseScene : public testing::TestWithParam<const char*> {};

TEST_P(ShowcaseScene, PassesAtFullLengthWithTheAdaptiveStep) {
  // As `springy check SCENE --tolerance 1e-4` runs it: under the monitor at every frame, with no
  // step given (the scenes' own steps and substeps are what the adaptive step replaces).
  const SceneDesc scene = loadScene(scenePath(GetParam()));
  PathSettings s;
  s.integrator = Integrator::BogackiShampine;
  s.dt = scene.dt;
  s.tolerance = SimulationDesc{}.tolerance;
  s.frame = 1.0 / scene.view.render.fps;
  s.duration = scene.duration;
  s.threads = 2;
  const RunPath path = tracePath(buildModel(scene), s);
  EXPECT_TRUE(path.complete) << GetParam() << ": " << path.failure;
  EXPECT_NEAR(path.times.back(), scene.duration, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Scenes, ShowcaseScene,
                         testing::Values("single_sphere", "spheres", "fixed_single_sphere", "cube", "ramp", "jelly",
                                         "bunny", "bunny_light"));

}  // namespace
}  // namespace springy

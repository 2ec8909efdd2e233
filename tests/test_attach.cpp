// Attachments ([[attach]]): vertices of a body held to a triangle collider, still or moving, or to
// another body, by a damped spring (soft) or exactly (hard, to a collider), until a release time.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/monitor.h"
#include "sim/world.h"

namespace springy {
namespace {

// A coarse gas ball (12 vertices) with no gravity, and a small plate far away that the springs
// hang from (nothing touches it).
constexpr const char* kBall = R"(
[scene]
dt = 0.0005
[environment]
gravity = [0, 0, 0]
[[body]]
name = "ball"
shape = "icosphere"
subdivisions = 0
radius = 0.3
mass = 1.0
position = [0.0, 1.0, 0.0]
velocity = [0.4, 0.0, -0.2]
[[triangles]]
name = "hook"
quads = [[[-0.1, 5, -0.1], [-0.1, 5, 0.1], [0.1, 5, 0.1], [0.1, 5, -0.1]]]
)";

// `points = [...]` naming every vertex of the scene's first body.
std::string everyVertex(const std::string& text) {
  const SceneDesc scene = parseScene(text, "ball.toml");
  std::string list = "points = [";
  for (const Vec3& p : scene.bodies[0].mesh.positions) {
    char item[128];
    std::snprintf(item, sizeof item, "[%.17g, %.17g, %.17g], ", p.x, p.y, p.z);
    list += item;
  }
  return list + "]\n";
}

// Every vertex on a spring of period P and decay time T to the hook, which stays put or moves at
// a constant velocity V. Each spring's stiffness is its vertex's mass times omega^2 and its
// damping twice the mass over T, so whatever the struts and the gas do inside the ball, its
// centroid's offset from where the hook carries its start, delta = c - c0 - V t, is a damped
// oscillator: delta'' + (2/T) delta' + omega^2 delta = 0, delta(0) = 0, delta'(0) = v0 - V:
//   delta(t) = (v0 - V) exp(-t/T) sin(omega_d t) / omega_d,  omega_d^2 = omega^2 - 1/T^2.
TEST(Attachments, ASoftSpringGivesItsPeriodAndDecay) {
  const double period = 0.5, decay = 2.0, omega = 2.0 * M_PI / period;
  const double omegaD = std::sqrt(omega * omega - 1.0 / (decay * decay));
  const Vec3 v0{0.4, 0.0, -0.2};
  for (const Vec3 hookVelocity : {Vec3{}, Vec3{-0.3, 0.5, 0.0}}) {
    std::string text = std::string(kBall);
    if (length(hookVelocity) > 0.0) {
      char keys[160];
      std::snprintf(keys, sizeof keys, "[triangles.motion]\nkeys = [[0, 0, 0, 0], [3, %g, %g, %g]]\n",
                    3.0 * hookVelocity.x, 3.0 * hookVelocity.y, 3.0 * hookVelocity.z);
      text += keys;
    }
    text += "[[attach]]\nbody = \"ball\"\nto = \"hook\"\nperiod = 0.5\ndecay = 2.0\n" + everyVertex(kBall);
    const SceneDesc scene = parseScene(text, "ball.toml");
    World world(buildModel(scene), Integrator::RK4, stepSize(scene));
    const Vec3 c0 = measureBody(world, 0).centroid;
    const double amplitude = length(v0 - hookVelocity) / omegaD;
    double worst = 0.0, reach = 0.0;
    while (world.time() < 2.0 - 1e-9) {
      world.step();
      const double t = world.time();
      const Vec3 want = (v0 - hookVelocity) * (std::exp(-t / decay) * std::sin(omegaD * t) / omegaD);
      const Vec3 delta = measureBody(world, 0).centroid - c0 - hookVelocity * t;
      worst = std::max(worst, length(delta - want));
      reach = std::max(reach, length(delta));
    }
    EXPECT_LT(worst, 1e-6 * amplitude) << "hook velocity " << hookVelocity.y;
    EXPECT_GT(reach, 0.5 * amplitude);  // it did swing
  }
}

// Two balls, a vertex of one on a spring to the nearest vertex of the other (a spring with the
// rest length of their distance at the start), the first moving away: the spring pulls the
// second along. The forces are equal, opposite and along the line between the two ends, so the
// pair's momentum stays what it was to round-off (RK4 keeps a linear invariant exactly) and its
// angular momentum to the step's truncation error; after the release each ball keeps its own.
TEST(Attachments, TwoBodiesOnASpringKeepTheirMomentumAndGoTheirWaysOnRelease) {
  const std::string text = R"(
[scene]
dt = 0.0005
[environment]
gravity = [0, 0, 0]
[[body]]
name = "a"
shape = "icosphere"
subdivisions = 1
radius = 0.3
mass = 1.0
position = [-0.35, 1.0, 0.0]
velocity = [-1.0, 0.3, 0.0]
[[body]]
name = "b"
shape = "icosphere"
subdivisions = 1
radius = 0.3
mass = 2.0
position = [0.35, 1.0, 0.1]
[[attach]]
body = "a"
to = "b"
points = [[-0.05, 1.0, 0.0]]
period = 0.2
decay = 1.0
release = 0.5
)";
  const SceneDesc scene = parseScene(text, "pair.toml");
  const Model model = buildModel(scene);
  ASSERT_EQ(model.attachments.size(), 1u);
  const Model::Attachment& spring = model.attachments[0];
  EXPECT_GT(spring.rest, 0.09);  // the vertices' distance at the start
  // Its period is the pair's on their own: k = mu omega^2, mu their reduced mass.
  const double ma = model.mass[spring.vertex], mb = model.mass[spring.other], mu = ma * mb / (ma + mb);
  EXPECT_NEAR(spring.k, mu * std::pow(2.0 * M_PI / 0.2, 2), 1e-12 * spring.k);
  EXPECT_NEAR(spring.d, 2.0 * mu / 1.0, 1e-12 * spring.d);
  World world(model, Integrator::RK4, stepSize(scene));
  const auto total = [&] {
    const BodyMeasures a = measureBody(world, 0), b = measureBody(world, 1);
    return std::make_pair(a.momentum + b.momentum, a.angularMomentum + b.angularMomentum);
  };
  const auto [p0, l0] = total();
  while (world.time() < 0.5 - 1e-9) {
    world.step();
    const auto [p, l] = total();
    ASSERT_LT(length(p - p0), 1e-12) << world.time();
    ASSERT_LT(length(l - l0), 1e-9) << world.time();  // RK4 keeps it to its truncation error only
  }
  EXPECT_LT(measureBody(world, 1).momentum.x, -0.2);  // pulled along
  const Vec3 pa = measureBody(world, 0).momentum, pb = measureBody(world, 1).momentum;
  while (world.time() < 0.8 - 1e-9) world.step();  // (b, faster now, reaches a at 0.99 s)
  EXPECT_LT(length(measureBody(world, 0).momentum - pa), 1e-12);  // apart: no force between them
  EXPECT_LT(length(measureBody(world, 1).momentum - pb), 1e-12);
}

// A cloth's top edge held hard to a bar that swings about the vertical and rises: each held
// vertex is where the bar carries its start, to 1e-9, at the bar's velocity, at every step; let
// go at the release, they fall. The rest of the cloth hangs from them.
TEST(Attachments, AHardAttachmentFollowsAMovingColliderAndIsReleased) {
  const std::string text = R"(
[scene]
dt = 0.0005
[[body]]
name = "cape"
shape = "cloth"
size = [0.6, 0.6]
resolution = [6, 6]
rotation = [90, 0, 0]
position = [0.0, 2.0, 1.0]
mass = 0.2
[[triangles]]
name = "bar"
quads = [[[-0.4, 2.35, 0.95], [-0.4, 2.35, 1.05], [0.4, 2.35, 1.05], [0.4, 2.35, 0.95]]]
[triangles.motion]
spin = 60.0
centre = [0, 0, 0]
interpolation = "cubic"
keys = [[0, 0, 0, 0], [0.5, 0, 0.3, 0]]
[[attach]]
body = "cape"
to = "bar"
points = [[-0.3, 2.3, 1.0], [0.0, 2.3, 1.0], [0.3, 2.3, 1.0]]
release = 0.6
)";
  const SceneDesc scene = parseScene(text, "cape.toml");
  const Model model = buildModel(scene);
  ASSERT_EQ(model.pinned.size(), 3u);
  const Movement& motion = scene.triangleColliders[0].motion;
  World world(model, Integrator::RK4, stepSize(scene));
  double worst = 0.0;
  while (world.time() < 0.6 - 1e-9) {
    world.step();
    const Pose pose = motion.pose(world.time()), start = motion.pose(0.0);
    for (uint32_t i : model.pinned) {
      const Vec3 want = pose.apply(start.inverse(model.restPosition[i]));
      worst = std::max(worst, length(world.positions()[i] - want));
      ASSERT_LT(length(world.velocities()[i] - motion.velocityAt(want, world.time())), 1e-9);
    }
  }
  EXPECT_LT(worst, 1e-9);
  const double held = world.positions()[model.pinned[0]].y;
  while (world.time() < 1.0 - 1e-9) world.step();
  // Released in the run's state; the model stays as it was set up.
  for (uint32_t i : model.pinned) EXPECT_GT(world.inverseMasses()[i], 0.0);
  for (uint32_t i : model.pinned) EXPECT_EQ(world.model().invMass[i], 0.0);
  EXPECT_LT(world.positions()[model.pinned[0]].y, held - 0.2);  // free: it fell
}

std::vector<Vec3> runOn(const SceneDesc& scene, unsigned threads, double until) {
  World world(buildModel(scene), Integrator::RK4, stepSize(scene));
  world.setThreads(threads, 0);
  while (world.time() < until - 1e-9) world.step();
  return world.positions();
}

TEST(Attachments, BitIdenticalOnOneAndTwoThreads) {
  const std::string text = std::string(kBall) + R"(
[triangles.motion]
oscillate = [0.1, 0.05, 0.0]
frequency = 2.0
[[attach]]
body = "ball"
to = "hook"
points = [[0.0, 1.3, 0.0], [0.3, 1.0, 0.0]]
period = 0.3
[[body]]
name = "other"
shape = "icosphere"
subdivisions = 1
radius = 0.2
position = [0.0, 0.4, 0.0]
[[attach]]
body = "other"
to = "ball"
points = [[0.0, 0.6, 0.0]]
period = 0.2
decay = 0.5
release = 0.3
)";
  const SceneDesc scene = parseScene(text, "both.toml");
  const std::vector<Vec3> one = runOn(scene, 1, 0.5), two = runOn(scene, 2, 0.5);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(Vec3)), 0);
}

std::string errorIn(const std::string& text) {
  try {
    const SceneDesc scene = parseScene(text, "bad.toml");
    buildModel(scene);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(Attachments, BadAttachmentsAreClearErrors) {
  const std::string two = std::string(kBall) +
                          "[[body]]\nname = \"other\"\nshape = \"cube\"\nsize = 0.2\nposition = [1, 1, 0]\npin = [0]\n";
  const auto attach = [&](const std::string& keys) { return errorIn(two + "[[attach]]\n" + keys); };
  const std::string points = "points = [[0, 1.3, 0]]\n";
  EXPECT_NE(attach("body = \"bal\"\nto = \"hook\"\n" + points).find("no body is named 'bal'"), std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"hok\"\n" + points).find("nothing is named 'hok'"), std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"hok\"\n" + points).find("'ball', 'other', 'hook'"), std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"ball\"\nperiod = 1\n" + points).find("not attached to itself"),
            std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"other\"\n" + points).find("give period"), std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"hook\"\n").find("needs points"), std::string::npos);
  EXPECT_NE(attach("to = \"hook\"\n" + points).find("needs body"), std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"hook\"\ndecay = 1\n" + points).find("give its period too"),
            std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"hook\"\nperiod = -1\n" + points).find("period"), std::string::npos);
  EXPECT_NE(attach("body = \"ball\"\nto = \"hook\"\nlength = 1\n" + points).find("length"), std::string::npos);
  const Vec3 pin = parseScene(two, "two.toml").bodies[1].mesh.positions[0];
  EXPECT_NE(attach("body = \"other\"\nto = \"hook\"\npoints = [[" + std::to_string(pin.x) + ", " + std::to_string(pin.y) +
                   ", " + std::to_string(pin.z) + "]]\n")
                .find("pinned already"),
            std::string::npos);
  // Each names the file and the line of its table.
  const std::string lost = attach("body = \"ball\"\nto = \"hok\"\n" + points);
  EXPECT_NE(lost.find("bad.toml:"), std::string::npos) << lost;
  // backward_euler has no Jacobian for the springs: refused, with what to use.
  const SceneDesc scene = parseScene(std::string(kBall) + "[[attach]]\nbody = \"ball\"\nto = \"hook\"\nperiod = 1\n" + points,
                                     "ok.toml");
  try {
    World world(buildModel(scene), Integrator::BackwardEuler, 1e-3);
    ADD_FAILURE() << "backward_euler took a soft attachment";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("backward_euler"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace springy

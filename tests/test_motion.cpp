// Things that move on their own (sim/motion.h): the prescribed motion itself (keyframes, spin,
// oscillation), colliders that move with it (continuous contact in the collider's frame, friction
// relative to the surface), pins that follow a track and are released, the adaptive step landing
// on keyframes, the audit of bodies against collider triangles, and bit-identical results on any
// thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "fixtures.h"
#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/intersections.h"
#include "sim/monitor.h"
#include "sim/motion.h"
#include "sim/world.h"

namespace springy {
namespace {

constexpr double kG = 9.81;

Movement keyed(std::vector<Movement::Key> keys, bool cubic) {
  Movement m;
  m.keys = std::move(keys);
  m.cubic = cubic;
  return m;
}

// Central difference of the translation, the derivative the motion claims.
Vec3 differenced(const Movement& m, const Vec3& p, double t, double h = 1e-6) {
  return (m.pose(t + h).apply(p) - m.pose(t - h).apply(p)) / (2.0 * h);
}

// ---------------------------------------------------------------------------------------------
// The motion.

TEST(Movement, LinearKeysInterpolateAndHoldBeforeAndAfter) {
  const Movement m = keyed({{1.0, {0, 0, 0}}, {2.0, {2, -4, 6}}, {4.0, {2, 0, 6}}}, false);
  EXPECT_TRUE(m.moves());
  EXPECT_EQ(length(m.translation(0.0)), 0.0);  // held before the first key
  EXPECT_EQ(length(m.translation(1.0)), 0.0);
  const Vec3 mid = m.translation(1.5);
  EXPECT_NEAR(mid.x, 1.0, 1e-15);
  EXPECT_NEAR(mid.y, -2.0, 1e-15);
  EXPECT_NEAR(mid.z, 3.0, 1e-15);
  EXPECT_NEAR(m.translation(3.0).y, -2.0, 1e-15);
  EXPECT_NEAR(m.translation(9.0).y, 0.0, 1e-15);  // held after the last
  EXPECT_NEAR(m.translationVelocity(1.5).y, -4.0, 1e-12);
  EXPECT_NEAR(m.translationVelocity(3.0).y, 2.0, 1e-12);
  EXPECT_EQ(length(m.translationVelocity(0.5)), 0.0);
  EXPECT_EQ(length(m.translationVelocity(5.0)), 0.0);
  EXPECT_EQ(m.kinks(), (std::vector<double>{1.0, 2.0, 4.0}));
}

TEST(Movement, CubicKeysPassThroughEveryKeyAreC1AndStartAndStopAtRest) {
  const Movement m = keyed({{0.5, {0, 0, 0}}, {1.5, {0, -0.7, 0.2}}, {2.0, {0.3, -0.7, 0}}, {3.0, {0, 1, 0}}}, true);
  for (const Movement::Key& k : m.keys) {
    EXPECT_LT(length(m.translation(k.time) - k.offset), 1e-15) << k.time;
  }
  EXPECT_LT(length(m.translationVelocity(0.5)), 1e-15);  // zero tangents at the ends
  EXPECT_LT(length(m.translationVelocity(3.0)), 1e-15);
  // The velocity is the derivative of the translation everywhere, and continuous across keys.
  for (double t = 0.513; t < 3.0; t += 0.05) {  // off the keys (the acceleration jumps there)
    const Vec3 fd = differenced(m, {0, 0, 0}, t);
    EXPECT_LT(length(fd - m.translationVelocity(t)), 1e-8) << t;
  }
  for (const Movement::Key& k : m.keys) {
    EXPECT_LT(length(m.translationVelocity(k.time - 1e-9) - m.translationVelocity(k.time + 1e-9)), 1e-6) << k.time;
  }
}

// Cubic keys never overshoot (monotone tangents): a hold between two equal keys stays put, and
// the path stays between the keys on each side of it.
TEST(Movement, CubicKeysHoldBetweenEqualKeysAndNeverOvershoot) {
  const Movement m = keyed({{0.3, {0, 0, 0}}, {1.5, {0, -0.7, 0}}, {2.2, {0, -0.7, 0}}, {3.2, {0, 0.4, 0}}}, true);
  for (double t = 1.5; t <= 2.2; t += 0.01) EXPECT_NEAR(m.translation(t).y, -0.7, 1e-15) << t;
  for (double t = 0.0; t <= 3.5; t += 0.005) {
    EXPECT_GE(m.translation(t).y, -0.7 - 1e-15) << t;
    EXPECT_LE(m.translation(t).y, 0.4) << t;
  }
  // Where the keys climb steadily the tangent is Catmull-Rom's: evenly spaced keys on a line
  // are followed exactly.
  const Movement line = keyed({{0, {0, 0, 0}}, {1, {1, 2, 0}}, {2, {2, 4, 0}}, {3, {3, 6, 0}}}, true);
  EXPECT_NEAR(line.translation(1.5).y, 3.0, 1e-15);
  EXPECT_NEAR(line.translationVelocity(1.5).y, 2.0, 1e-14);
}

TEST(Movement, SpinAndOscillationVelocityIsTheDerivativeOfThePose) {
  Movement m = keyed({{0.0, {0, 0, 0}}, {2.0, {1, 0.5, 0}}}, true);
  m.spin = 1.3;
  m.axis = normalized(Vec3{0.2, 1.0, -0.3});
  m.centre = {0.4, -1.0, 2.0};
  m.amplitude = {0.05, 0.1, 0.0};
  m.frequency = 2.5;
  m.phase = 0.7;
  const Vec3 p{1.0, 2.0, -0.5};
  for (double t = 0.05; t < 3.0; t += 0.1) {
    const Pose pose = m.pose(t);
    // A rotation: lengths kept, and inverse undoes apply.
    EXPECT_NEAR(length(pose.rotate(p)), length(p), 1e-14);
    EXPECT_LT(length(pose.inverse(pose.apply(p)) - p), 1e-14);
    const Vec3 x = pose.apply(p);
    EXPECT_LT(length(differenced(m, p, t) - m.velocityAt(x, t)), 1e-7) << t;
  }
  // The spin alone turns by spin x t about the axis through the centre.
  Movement spin;
  spin.spin = 0.5;
  spin.centre = {1, 0, 0};
  const Vec3 q = spin.pose(kPi).apply({2, 0, 0});  // a quarter turn about +y from (1, 0, 0)
  EXPECT_NEAR(q.x, 1.0, 1e-14);
  EXPECT_NEAR(q.z, -1.0, 1e-14);
}

// ---------------------------------------------------------------------------------------------
// Moving colliders.

// A vertex resting on a plane that rises at 0.5 m/s under gravity: it is carried up, never
// behind the plane, and its velocity relative to the plane goes to zero.
TEST(MovingColliders, AVertexRestsOnAPlaneRisingAtConstantSpeed) {
  for (const Integrator integrator : {Integrator::RK4, Integrator::VelocityVerlet, Integrator::SymplecticEuler}) {
    Model model = vertexModel({0.3, 0.02, -0.1}, {0, 0, 0}, {0, -kG, 0});
    PlaneCollider plane;
    plane.normal = {0, 1, 0};
    plane.material = {0.0, 0.5};
    plane.motion = keyed({{0.0, {0, 0, 0}}, {10.0, {0, 5.0, 0}}}, false);  // 0.5 m/s up
    model.colliders.planes.push_back(plane);
    model.colliders.restingSpeed = 4.0 * kG * 1e-3;
    World world(std::move(model), integrator, 1e-3);
    for (int s = 0; s < 2000; ++s) {
      world.step();
      ASSERT_GE(world.positions()[0].y, 0.5 * world.time() - 1e-12) << integratorName(integrator) << " step " << s;
    }
    const Vec3 relative = world.velocities()[0] - Vec3{0, 0.5, 0};
    EXPECT_LT(length(relative), 1e-9) << integratorName(integrator);
    // On the surface, within the contact's skin.
    EXPECT_NEAR(world.positions()[0].y, 0.5 * world.time(), 1.01 * world.model().colliders.skin)
        << integratorName(integrator);
    EXPECT_NEAR(world.positions()[0].x, 0.3, 1e-12);  // nothing pushed it sideways
  }
}

constexpr const char* kBall = R"(
[[body]]
name = "ball"
shape = "icosphere"
subdivisions = 2
radius = 0.3
position = [0.0, 0.32, 0.0]
mass = 1.0
volume_period = 0.3
)";

// A soft ball on a plate rising at constant speed: it rides it, none of its vertices ever under
// it, its centroid rising at the plate's speed; the bounce the plate's start gave it (its squash
// mode, period about 0.75 s) dies away, so its velocity relative to the plate goes to zero.
TEST(MovingColliders, ASoftBallRestsOnAPlateRisingAtConstantSpeed) {
  const std::string text = std::string("[scene]\ndt = 0.001\n") + kBall + R"(
[[triangles]]
name = "plate"
quads = [[[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]]]
restitution = 0.0
friction = 0.5
[triangles.motion]
keys = [[0.5, 0, 0, 0], [10.5, 0, 5, 0]]
)";
  const SceneDesc scene = parseScene(text, "rise.toml");
  World world(buildModel(scene), Integrator::RK4, stepSize(scene));
  Monitor monitor(world);
  const auto plateAt = [](double t) { return t <= 0.5 ? 0.0 : 0.5 * (t - 0.5); };
  const double mass = world.model().bodies[0].mass;
  double early = 0.0, late = 0.0;  // the largest |v - 0.5| of the centroid over 1-2.5 s, 4.5-6 s
  double at2 = 0.0;                // the centroid's height at 2 s
  for (int s = 1; s <= 6000; ++s) {
    world.step();
    for (const Vec3& x : world.positions()) ASSERT_GE(x.y, plateAt(world.time()) - 1e-9) << "step " << s;
    const BodyMeasures m = measureBody(world, 0);
    const double off = std::fabs(m.momentum.y / mass - 0.5);
    if (s >= 1000 && s <= 2500) early = std::max(early, off);
    if (s >= 4500) late = std::max(late, off);
    if (s == 2000) at2 = m.centroid.y;
    if (s % 33 == 0) {
      const std::optional<Failure> failure = monitor.check(world);
      ASSERT_FALSE(failure) << failure->message;
    }
  }
  const BodyMeasures m = measureBody(world, 0);
  EXPECT_NEAR((m.centroid.y - at2) / (world.time() - 2.0), 0.5, 0.005);  // carried up at its speed
  EXPECT_GT(early, 0.05);         // the start set it bouncing
  EXPECT_LT(late, 0.25 * early);  // and the bounce dies away
  double lowest = 1e9;
  for (const Vec3& x : world.positions()) lowest = std::min(lowest, x.y);
  EXPECT_NEAR(lowest, plateAt(world.time()), 1e-3);  // on it
  EXPECT_GT(m.volume / world.model().bodies[0].restVolume, 0.95);
}

// A plate turning at 30 deg/s about the vertical through its centre carries a body resting on
// it round with it by friction (mu g = 5.9 m/s^2 holds the 0.27 m/s^2 the turn needs at 1 m);
// a frictionless one leaves it where it was.
TEST(MovingColliders, ATurningPlateCarriesARestingBodyByFriction) {
  for (const double friction : {0.0, 0.6}) {
    const std::string text = "[scene]\ndt = 0.001\n" + std::string(R"(
[[body]]
name = "cube"
shape = "cube"
size = 0.2
position = [1.0, 0.101, 0.0]
mass = 0.5
contact_friction = )") + std::to_string(friction) + R"(
[[triangles]]
name = "turntable"
quads = [[[-2, 0, -2], [-2, 0, 2], [2, 0, 2], [2, 0, -2]]]
restitution = 0.0
friction = )" + std::to_string(friction) + R"(
[triangles.motion]
spin = 30.0
)";
    const SceneDesc scene = parseScene(text, "turntable.toml");
    World world(buildModel(scene), Integrator::RK4, stepSize(scene));
    const double turn = 30.0 * kPi / 180.0;
    while (world.time() < 4.0 - 1e-9) world.step();
    const Vec3 c = measureBody(world, 0).centroid;
    const double angle = std::atan2(-c.z, c.x);  // +y spin turns +x toward -z
    if (friction == 0.0) {
      EXPECT_LT(std::hypot(c.x - 1.0, c.z), 0.01) << "friction 0";
    } else {
      // It lags the table by the distance the table slid under it while friction brought it up
      // to the table's speed v = omega r: v^2 / (2 mu g), an angle of omega^2 r / (2 mu g).
      const double lag = turn * turn * 1.0 / (2.0 * friction * kG);
      EXPECT_NEAR(turn * world.time() - angle, lag, 0.15 * lag) << "friction " << friction;
      EXPECT_NEAR(std::hypot(c.x, c.z), 1.0, 0.01);
      // And moves with the table: the velocity of the table under its centroid.
      const Vec3 v = measureBody(world, 0).momentum / world.model().bodies[0].mass;
      EXPECT_NEAR(length(v), turn * std::hypot(c.x, c.z), 0.01);
    }
  }
}

// A plate at 20 m/s (8.3 cm a step at dt 1/240 s) runs into a soft ball in free space: no
// vertex ever gets through it, and the ball leaves at the plate's speed or faster. The ball is
// coarse (42 vertices, 0.19 m edges) and as stiff as dt 1/240 s allows (`springy suggest`:
// stretch_period >= 0.039 s): it is squashed to a third of its volume and springs back.
TEST(MovingColliders, AColliderAt20MetresASecondNeverTunnelsThroughABall) {
  for (const bool plane : {false, true}) {
    std::string text = std::string("[scene]\ndt = 0.0041666666666666666\nintegrator = \"rk4\"\n") +
                       "[environment]\ngravity = [0, 0, 0]\n" + R"(
[[body]]
name = "ball"
shape = "icosphere"
subdivisions = 1
radius = 0.3
position = [0.0, 0.32, 0.0]
mass = 1.0
volume_period = 0.1
stretch_period = 0.045
bend_period = 0.6
)";
    text += plane ? "[[plane]]\npoint = [0, 1.5, 0]\nnormal = [0, -1, 0]\nrestitution = 0.5\n[plane.motion]\n"
                  : "[[triangles]]\nname = \"plate\"\nquads = [[[-1, 1.5, -1], [-1, 1.5, 1], [1, 1.5, 1], [1, 1.5, -1]]]\n"
                    "restitution = 0.5\n[triangles.motion]\n";
    text += "keys = [[0, 0, 0, 0], [1, 0, -20, 0]]\n";
    const SceneDesc scene = parseScene(text, "hammer.toml");
    World world(buildModel(scene), Integrator::RK4, stepSize(scene));
    Monitor monitor(world);
    bool hit = false;
    for (int s = 1; s <= 120; ++s) {
      world.step();
      const double plateY = 1.5 - 20.0 * world.time();
      for (const Vec3& x : world.positions()) {
        ASSERT_LE(x.y, plateY + 1e-9) << (plane ? "plane" : "plate") << " step " << s;
      }
      hit = hit || measureBody(world, 0).momentum.y < 0.0;
      if (s % 8 == 0) {
        const std::optional<Failure> failure = monitor.check(world);
        ASSERT_FALSE(failure) << failure->message;
      }
    }
    EXPECT_TRUE(hit);
    EXPECT_LT(measureBody(world, 0).momentum.y, -20.0 * 1.0 * 0.99) << (plane ? "plane" : "plate");
  }
}

// ---------------------------------------------------------------------------------------------
// Pins that follow a track.

// A cloth held along its top edge by pins that turn about the vertical and slide along a cubic
// track: every pinned vertex is where the motion puts its rest position, to 1e-9, at every
// step, with the motion's velocity; let go at pin_release, they fall.
TEST(PinTracks, PinnedVerticesFollowTheTrackAndAreReleased) {
  const std::string text = R"(
[scene]
dt = 0.0005
[[body]]
name = "cape"
shape = "cloth"
size = [0.6, 0.6]
resolution = [8, 8]
rotation = [90, 0, 0]
position = [0.0, 2.0, 1.0]
mass = 0.2
pin_side = "top"
pin_release = 0.8
[body.pin_motion]
spin = 90.0
interpolation = "cubic"
keys = [[0, 0, 0, 0], [0.4, 0.3, 0.2, 0], [0.9, 0, 0, 0]]
)";
  const SceneDesc scene = parseScene(text, "cape.toml");
  const Model model = buildModel(scene);
  ASSERT_EQ(model.pinned.size(), 9u);
  const Movement& motion = scene.bodies[0].pinMotion;
  World world(model, Integrator::RK4, stepSize(scene));
  double worst = 0.0;
  while (world.time() < 0.8 - 1e-9) {
    world.step();
    for (uint32_t i : model.pinned) {
      const Vec3 want = motion.pose(world.time()).apply(model.restPosition[i]);
      worst = std::max(worst, length(world.positions()[i] - want));
      ASSERT_LT(length(world.velocities()[i] - motion.velocityAt(want, world.time())), 1e-9);
    }
  }
  EXPECT_LT(worst, 1e-9);
  const double top = world.positions()[model.pinned[0]].y;
  while (world.time() < 1.2 - 1e-9) world.step();
  // Released in the run's state; the model stays as it was set up.
  for (uint32_t i : model.pinned) EXPECT_GT(world.inverseMasses()[i], 0.0);
  for (uint32_t i : model.pinned) EXPECT_EQ(world.model().invMass[i], 0.0);
  EXPECT_LT(world.positions()[model.pinned[0]].y, top - 0.3);  // free: it fell
}

// The implicit integrators release pins too: their solves hold a vertex whose inverse mass is 0,
// and after the release it is the run's 1 / m (State::invMass), not the model's 0 (backward
// Euler's filter of held rows was built once, so its released pins flew on at their last
// velocity, unmoved by gravity or springs).
TEST(PinTracks, TheImplicitIntegratorsLetReleasedPinsFall) {
  const std::string text = R"(
[scene]
dt = 0.005
[[body]]
name = "cloth"
shape = "cloth"
size = [0.6, 0.6]
resolution = [6, 6]
rotation = [90, 0, 0]
position = [0.0, 2.0, 0.0]
mass = 0.2
pin_side = "top"
pin_release = 0.2
)";
  const SceneDesc scene = parseScene(text, "release.toml");
  const Model model = buildModel(scene);
  ASSERT_FALSE(model.pinned.empty());
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::Vbd}) {
    World world(model, integrator, stepSize(scene));
    while (world.time() < 0.2 - 1e-9) world.step();
    const double held = world.positions()[model.pinned[0]].y;
    EXPECT_NEAR(held, model.restPosition[model.pinned[0]].y, 1e-12) << integratorName(integrator);
    while (world.time() < 0.5 - 1e-9) world.step();
    // Released at rest, in free fall with the cloth (g t^2 / 2 = 0.44 m over 0.3 s; the cloth's
    // own springs pull on it too): well below where it was held, and moving down.
    const uint32_t pin = model.pinned[0];
    EXPECT_LT(world.positions()[pin].y, held - 0.2) << integratorName(integrator);
    EXPECT_LT(world.velocities()[pin].y, -1.0) << integratorName(integrator);
  }
}

// ---------------------------------------------------------------------------------------------
// The adaptive step, the audit, threads.

TEST(MovingColliders, TheAdaptiveStepLandsOnEveryKeyframeAndTheRelease) {
  const std::string text = std::string("[scene]\ntolerance = 1e-4\n") + kBall + R"(pin = [0]
pin_release = 0.47
[[triangles]]
name = "plate"
quads = [[[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]]]
[triangles.motion]
keys = [[0.13, 0, 0, 0], [0.37, 0, 0.2, 0], [0.61, 0, 0.1, 0]]
)";
  const SceneDesc scene = parseScene(text, "keys.toml");
  for (const Integrator integrator : {Integrator::BogackiShampine, Integrator::AdaptiveVerlet}) {
    World world(buildModel(scene), integrator, stepSize(scene));
    world.setTolerance(scene.tolerance);
    std::vector<double> times;
    while (world.time() < 1.0) {
      world.stepToward(1.0);
      times.push_back(world.time());
    }
    for (double t : {0.13, 0.37, 0.47, 0.61, 1.0}) {
      EXPECT_NE(std::find(times.begin(), times.end(), t), times.end())
          << t << " s not landed on by " << integratorName(integrator);
    }
  }
}

constexpr const char* kCrossing = R"(
[[body]]
name = "cube"
shape = "cube"
size = 0.5
position = [0.0, 1.0, 0.0]
[[triangles]]
name = "blade"
quads = [[[-1, 1.0, -1], [-1, 1.0, 1], [1, 1.0, 1], [1, 1.0, -1]]]
)";

TEST(ColliderAudit, CatchesABodyThroughAStillOrMovingColliderAndNamesIt) {
  // The blade through the cube's middle.
  const Model through = buildModel(parseScene(kCrossing, "through.toml"));
  const std::vector<ColliderCrossing> found = findColliderCrossings(through, through.restPosition, 0.0);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found[0].body, 0u);
  EXPECT_EQ(found[0].collider, 0u);
  EXPECT_NEAR(found[0].point.y, 1.0, 1e-12);
  World world(through, Integrator::RK4, 1e-3);
  Monitor monitor(world);
  const std::optional<Failure> failure = monitor.check(world);
  ASSERT_TRUE(failure);
  EXPECT_NE(failure->message.find("passes through collider 'blade'"), std::string::npos) << failure->message;
  EXPECT_NE(failure->message.find("'cube'"), std::string::npos) << failure->message;

  // A blade that moves: clear of the cube at rest (0.6 m above), through it from 1 s on.
  const Model moving = buildModel(parseScene(std::string(kCrossing) + "[triangles.motion]\n"
                                                                      "keys = [[0, 0, 0.6, 0], [1, 0, 0, 0]]\n",
                                             "moving.toml"));
  EXPECT_TRUE(findColliderCrossings(moving, moving.restPosition, 0.0).empty());
  EXPECT_FALSE(findColliderCrossings(moving, moving.restPosition, 1.0).empty());
  // A body resting on a collider (a micrometre above, as its contact leaves it) does not cross it.
  const std::string resting =
      std::string(kCrossing).replace(std::string(kCrossing).find("1.0, 0.0]"), 9, "1.250001, 0.0]");
  const Model onIt = buildModel(parseScene(resting, "resting.toml"));
  EXPECT_TRUE(findColliderCrossings(onIt, onIt.restPosition, 0.0).empty());
}

std::vector<Vec3> runOn(const SceneDesc& scene, unsigned threads, double until) {
  World world(buildModel(scene), scene.integrator, stepSize(scene));
  world.setThreads(threads, 0);
  while (world.time() < until - 1e-9) world.step();
  return world.positions();
}

TEST(MovingColliders, BitIdenticalOnOneAndTwoThreads) {
  const std::string shaken = std::string("[scene]\ndt = 0.001\n") + kBall + R"(
[[triangles]]
name = "plate"
quads = [[[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]]]
[triangles.motion]
oscillate = [0.04, 0.02, 0.0]
frequency = 3.0
spin = 20.0
[[body]]
name = "cloth"
shape = "cloth"
size = [0.5, 0.5]
resolution = [6, 6]
position = [0.0, 1.2, 0.0]
pin_side = "left"
[body.pin_motion]
keys = [[0, 0, 0, 0], [0.3, 0.2, 0.1, 0]]
interpolation = "cubic"
)";
  const SceneDesc scene = parseScene(shaken, "shaken.toml");
  const std::vector<Vec3> one = runOn(scene, 1, 0.4), two = runOn(scene, 2, 0.4);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(Vec3)), 0);
}

// ---------------------------------------------------------------------------------------------
// Scene errors.

std::string errorIn(const std::string& text) {
  try {
    parseScene(text, "bad.toml");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(MotionKeys, BadMotionsAreClearErrors) {
  const std::string plate = "[[triangles]]\nquads = [[[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]]]\n[triangles.motion]\n";
  EXPECT_NE(errorIn(plate + "keys = [[0, 0, 0, 0], [0, 1, 0, 0]]\n").find("keyframe times must increase"),
            std::string::npos);
  EXPECT_NE(errorIn(plate + "keys = [[0, 0, 0]]\n").find("each keyframe is [t, x, y, z]"), std::string::npos);
  EXPECT_NE(errorIn(plate + "oscillate = [0, 1, 0]\n").find("needs both oscillate"), std::string::npos);
  EXPECT_NE(errorIn(plate + "axis = [0, 0, 0]\nspin = 5\n").find("must not be zero"), std::string::npos);
  EXPECT_NE(errorIn(plate + "spim = 5\n").find("spim"), std::string::npos);
  EXPECT_NE(errorIn(plate + "interpolation = \"cubic\"\n").find("does not move"), std::string::npos);
  EXPECT_NE(errorIn("[[body]]\nshape = \"cube\"\npin_release = 1.0\n").find("pin some"), std::string::npos);
  EXPECT_NE(errorIn("[[plane]]\ndamping = 1\ndamping_layer = 0.1\n[plane.motion]\nspin = 3\n").find("soft ground"),
            std::string::npos);
  // Each names the file and the line.
  EXPECT_NE(errorIn(plate + "keys = [[0, 0, 0, 0], [0, 1, 0, 0]]\n").find("bad.toml:4"), std::string::npos)
      << errorIn(plate + "keys = [[0, 0, 0, 0], [0, 1, 0, 0]]\n");
}

// ---------------------------------------------------------------------------------------------
// Crushes (docs/model.md section 19): two hollow balls of the seed's element material meeting
// head-on at 10 m/s. Without self contact one folds through itself and turns inside out, and the
// run stops saying so and naming the fix; with it, its own faces stop the fold.
std::string crushScene(bool selfContact) {
  std::string text = "[scene]\ndt = 0.001\n[environment]\ngravity = [0, 0, 0]\n";
  for (const double side : {-1.0, 1.0}) {
    text += "[[body]]\nshape = \"icosphere\"\nsubdivisions = 3\nradius = 0.5\nmass = 1.0\n"
            "strut_period = 0.05\nhinge_period = 0.2\n";
    text += std::string("name = \"") + (side < 0 ? "left" : "right") + "\"\n";
    text += "position = [" + std::to_string(1.5 * side) + ", 0, " + std::to_string(side > 0 ? 0.05 : 0.0) + "]\n";
    text += "velocity = [" + std::to_string(-10.0 * side) + ", 0, 0]\n";
    text += std::string("self_contact = ") + (selfContact ? "true" : "false") + "\n";
  }
  return text;
}

TEST(Crushes, ABallThatTurnsInsideOutStopsTheRunAndSelfContactPreventsIt) {
  for (const bool selfContact : {false, true}) {
    const SceneDesc scene = parseScene(crushScene(selfContact), "crush.toml");
    World world(buildModel(scene), Integrator::RK4, stepSize(scene));
    MonitorLimits limits;
    limits.minVolume = 0.0;  // as springy check: a body inside out fails
    Monitor monitor(world, limits);
    std::optional<Failure> failure;
    while (!failure && world.time() < 0.3 - 1e-9) {
      for (int s = 0; s < 10; ++s) world.step();
      failure = monitor.check(world);
    }
    if (!selfContact) {
      ASSERT_TRUE(failure) << "the crush no longer folds a ball through itself: update docs/model.md section 19";
      EXPECT_NE(failure->message.find("self_contact = true"), std::string::npos) << failure->message;
    } else {
      EXPECT_FALSE(failure) << failure->message;
      for (const BodyRecord& r : monitor.records()) EXPECT_GT(r.minVolumeRatio, 0.0);
    }
  }
}

}  // namespace
}  // namespace springy

// Contact between bodies and within a body (sim/contact.h) and its audit (sim/intersections.h).
#include <gtest/gtest.h>

#include <cmath>

#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/intersections.h"
#include "sim/monitor.h"
#include "sim/setup.h"
#include "sim/shapes.h"
#include "sim/world.h"

namespace springy {
namespace {

TriMesh moved(TriMesh mesh, const Vec3& by) {
  for (Vec3& p : mesh.positions) p += by;
  return mesh;
}

// A ball of the body material (162 vertices, 0.5 m, 1 kg) at `at`, moving at `velocity`.
BodyDesc ball(const std::string& name, const Vec3& at, const Vec3& velocity, bool contact = true) {
  BodyDesc desc;
  desc.name = name;
  desc.mesh = moved(makeIcosphere(0.5, 2), at);
  desc.velocity = velocity;
  desc.mass = 1.0;
  desc.material = MaterialModel::Body;
  desc.contact = contact;
  return desc;
}

Model twoBalls(bool contact, double speed = 4.0) {
  Model model;
  model.gravity = {};
  addBody(model, ball("left", {-1.2, 0.0, 0.0}, {speed, 0.0, 0.0}, contact));
  addBody(model, ball("right", {1.2, 0.1, 0.05}, {-speed, 0.0, 0.0}, contact));
  return model;
}

constexpr double kStep = 2e-4;  // under half the advisor's limit for these balls (rk4)

Vec3 momentum(const World& world) {
  Vec3 p;
  for (std::size_t i = 0; i < world.model().vertexCount(); ++i) p += world.velocities()[i] * world.model().mass[i];
  return p;
}

double totalEnergy(const World& world) {
  double e = 0.0;
  for (uint32_t b = 0; b < world.model().bodies.size(); ++b) e += measureBody(world, b).total();
  return e;
}

TEST(Intersections, FindsCrossingBodiesAndNothingElse) {
  Model model;
  model.gravity = {};
  addBody(model, ball("a", {0.0, 0.0, 0.0}, {}));
  addBody(model, ball("b", {0.8, 0.0, 0.0}, {}));  // overlaps a by 0.2 m
  addBody(model, ball("c", {5.0, 0.0, 0.0}, {}));  // far from both
  const std::vector<Intersection> found = findIntersections(model, model.restPosition, 1000);
  ASSERT_FALSE(found.empty());
  for (const Intersection& i : found) {
    EXPECT_EQ(i.bodyA, 0u);
    EXPECT_EQ(i.bodyB, 1u);
    // The two spheres' surfaces meet on the circle x = 0.4, radius sqrt(0.25 - 0.16) = 0.3.
    EXPECT_NEAR(i.point.x, 0.4, 0.03);
    EXPECT_NEAR(std::hypot(i.point.y, i.point.z), 0.3, 0.03);
  }
  // Moved apart, nothing; a body's own faces (self contact on) do not count their neighbours.
  model.bodies[0].selfContact = true;
  std::vector<Vec3> apart = model.restPosition;
  for (uint32_t i = model.bodies[1].firstVertex; i < model.bodies[1].firstVertex + model.bodies[1].vertexCount; ++i) {
    apart[i].x += 1.0;
  }
  EXPECT_TRUE(findIntersections(model, apart).empty());
  // A body pushed through itself: one vertex of a ball pulled across to the far side.
  std::vector<Vec3> folded = apart;
  const uint32_t top = 0;  // a vertex of ball a, pushed through the opposite side
  folded[top] = folded[top] * -1.6;
  const std::vector<Intersection> self = findIntersections(model, folded);
  ASSERT_FALSE(self.empty());
  EXPECT_EQ(self[0].bodyA, 0u);
  EXPECT_EQ(self[0].bodyB, 0u);
}

TEST(Intersections, SegmentThroughTriangle) {
  Vec3 point;
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  EXPECT_TRUE(segmentCrossesTriangle({0.2, 0.2, -1}, {0.2, 0.2, 1}, a, b, c, point));
  EXPECT_NEAR(point.x, 0.2, 1e-15);
  EXPECT_NEAR(point.z, 0.0, 1e-15);
  EXPECT_FALSE(segmentCrossesTriangle({0.8, 0.8, -1}, {0.8, 0.8, 1}, a, b, c, point));   // beside it
  EXPECT_FALSE(segmentCrossesTriangle({0.2, 0.2, 0.5}, {0.2, 0.2, 1}, a, b, c, point));  // short of it
}

// Without contact two balls thrown at each other pass through each other (the audit sees it);
// with it they meet, do not cross at any step, and fly apart, keeping the momentum (no gravity,
// no colliders: the contact's impulses are the only forces between them) and never gaining
// energy.
TEST(BodyContact, BallsThrownAtEachOtherBounceApartWithoutCrossing) {
  {
    World ghost(twoBalls(false), Integrator::RK4, kStep);
    EXPECT_EQ(ghost.bodyContacts(), nullptr);  // contact off: no stage
    bool crossed = false;
    for (int s = 0; s < 1500 && !crossed; ++s) {
      ghost.step();
      crossed = !findIntersections(ghost.model(), ghost.positions(), 1).empty();
    }
    Model audited = twoBalls(true);  // the audit of bodies that take part
    World probe(std::move(audited), Integrator::RK4, kStep);
    probe.setState(ghost.positions(), ghost.velocities(), ghost.time());
    EXPECT_FALSE(findIntersections(probe.model(), probe.positions(), 1).empty());
  }
  World world(twoBalls(true), Integrator::RK4, kStep);
  ASSERT_NE(world.bodyContacts(), nullptr);
  const Vec3 p0 = momentum(world);
  double energy = totalEnergy(world);
  const double scale = energy;
  ContactStats total;
  for (int s = 0; s < 3000; ++s) {
    world.step();
    total.add(world.bodyContacts()->lastStep());
    if (s % 10 == 0) {
      ASSERT_TRUE(findIntersections(world.model(), world.positions(), 1).empty()) << "crossed at step " << s;
      const double e = totalEnergy(world);
      EXPECT_LE(e, energy + 1e-6 * scale) << "energy rose at step " << s;
      energy = std::min(energy, e);
    }
  }
  EXPECT_GT(total.contacts, 0u);
  EXPECT_GT(total.impulses, 0u);
  const Vec3 p1 = momentum(world);
  EXPECT_NEAR(p1.x, p0.x, 1e-9);
  EXPECT_NEAR(p1.y, p0.y, 1e-9);
  EXPECT_NEAR(p1.z, p0.z, 1e-9);
  // They rebound: the left ball moves left, the right one right, and they are apart.
  const BodyMeasures left = measureBody(world, 0), right = measureBody(world, 1);
  EXPECT_LT(left.momentum.x, -0.5);
  EXPECT_GT(right.momentum.x, 0.5);
  EXPECT_GT(right.centroid.x - left.centroid.x, 1.0);
}

// A body in two pieces (two balls in one mesh) thrown together: with self contact the pieces
// meet and do not cross; without, they pass through each other.
TEST(BodyContact, SelfContactKeepsAPieceOfABodyOutOfAnother) {
  for (bool self : {false, true}) {
    TriMesh mesh = moved(makeIcosphere(0.5, 2), {-1.2, 0.0, 0.0});
    const TriMesh other = moved(makeIcosphere(0.5, 2), {1.2, 0.1, 0.0});
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), other.positions.begin(), other.positions.end());
    for (Triangle t : other.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    BodyDesc desc = ball("pair", {}, {});
    desc.mesh = mesh;
    desc.deformationDecay = 0.0;  // the pieces' approach is deformation of the one body
    desc.selfContact = self;
    Model model;
    model.gravity = {};
    addBody(model, desc);
    for (uint32_t i = 0; i < model.vertexCount(); ++i) model.initialVelocity[i] = {i < base ? 4.0 : -4.0, 0.0, 0.0};
    model.bodies[0].selfContact = true;  // audit the body's own faces either way
    Model stage = model;
    stage.bodies[0].selfContact = self;
    World world(std::move(stage), Integrator::RK4, kStep);
    bool crossed = false;
    for (int s = 0; s < 1500 && !crossed; ++s) {
      world.step();
      if (s % 10 == 0) crossed = !findIntersections(model, world.positions(), 1).empty();
    }
    EXPECT_EQ(crossed, !self) << (self ? "self contact let the pieces through" : "the pieces should pass through");
  }
}

// The same bits on 1, 2, 3 and 7 threads (the contact stage runs on one thread, in a fixed
// order; the forces are split by vertex ownership).
TEST(BodyContact, BitIdenticalOnAnyThreadCount) {
  std::vector<uint64_t> hashes;
  for (unsigned threads : {1u, 2u, 3u, 7u}) {
    World world(twoBalls(true), Integrator::RK4, kStep);
    world.setThreads(threads, 0);
    for (int s = 0; s < 1200; ++s) world.step();
    EXPECT_GT(world.bodyContacts()->sinceStart().contacts, 0u);
    hashes.push_back(stateHash(world));
  }
  for (std::size_t k = 1; k < hashes.size(); ++k) EXPECT_EQ(hashes[k], hashes[0]) << "thread count #" << k;
}

// One step of a body's vertex coming down at 5 m/s onto another body's face (the tip of an
// octahedron onto the top of a cube), resolved by the contact stage alone: the contact point's
// relative normal velocity at the end of the step is the restitution times the approach (the
// larger of the two bodies' restitution), and momentum is kept. Also when the end velocity
// approaches faster than the path (6 m/s at the end of a 5 m/s path, as RK4 ends a step that
// accelerates toward the face): the end velocity does not keep approaching.
TEST(BodyContact, AnImpactReboundsByTheRestitution) {
  for (double endSpeed : {5.0, 6.0})
    for (double restitution : {0.0, 0.5, 1.0}) {
      Model model;
      model.gravity = {};
      model.colliders.restingSpeed = 0.1;
      BodyDesc cube = ball("cube", {}, {});
      cube.mesh = makeCube(2.0, 1);  // top face at y = 1
      cube.contactThickness = 1e-3;
      cube.contactRestitution = 0.5 * restitution;  // the pair takes the larger
      BodyDesc tip = ball("tip", {}, {});
      tip.mesh = moved(makeOctahedronSphere(0.3, 1), {0.5, 1.0 + 0.3 + 0.02, -0.3});  // pole 2 cm above
      tip.contactThickness = 1e-3;
      tip.contactRestitution = restitution;
      addBody(model, cube);
      addBody(model, tip);
      const double dt = 0.01, speed = 5.0;  // 5 cm in the step: the pole meets the face at 0.4 of it
      const std::vector<Vec3> x0 = model.restPosition;
      std::vector<Vec3> x1 = x0, v1(x0.size());
      const BodyInfo& moving = model.bodies[1];
      uint32_t pole = moving.firstVertex;
      for (uint32_t i = moving.firstVertex; i < moving.firstVertex + moving.vertexCount; ++i) {
        v1[i] = {0.0, -endSpeed, 0.0};
        x1[i] = x0[i] + Vec3{0.0, -speed, 0.0} * dt;
        if (x0[i].y < x0[pole].y) pole = i;
      }
      Vec3 p0;
      for (uint32_t i = 0; i < x0.size(); ++i) p0 += v1[i] * model.mass[i];
      BodyContacts contacts(model);
      ASSERT_TRUE(contacts.resolve(x0, x1, v1, dt));
      EXPECT_EQ(contacts.lastStep().contacts, 1u);
      // The cube's face under the pole, and the weights of the pole's point on it.
      const Vec3 at = x0[pole];
      bool found = false;
      for (uint32_t f = 0; f < model.bodies[0].faceCount && !found; ++f) {
        const Triangle& t = model.faces[f];
        const PointTriangleClosest c = closestPointTriangle({at.x, 1.0, at.z}, x0[t[0]], x0[t[1]], x0[t[2]]);
        if (c.distanceSquared > 1e-20 || x0[t[0]].y != 1.0 || x0[t[1]].y != 1.0 || x0[t[2]].y != 1.0) continue;
        found = true;
        const double faceSpeed = c.weight[0] * v1[t[0]].y + c.weight[1] * v1[t[1]].y + c.weight[2] * v1[t[2]].y;
        EXPECT_NEAR(v1[pole].y - faceSpeed, restitution * speed, 1e-9 * speed)
            << "restitution " << restitution << ", end speed " << endSpeed;
        EXPECT_LT(v1[t[0]].y, 0.0);  // the face was pushed down
      }
      EXPECT_TRUE(found);
      Vec3 p1;
      for (uint32_t i = 0; i < x0.size(); ++i) p1 += v1[i] * model.mass[i];
      EXPECT_NEAR(length(p1 - p0), 0.0, 1e-12 * length(p0));
    }
}

// A ball resting on a ball resting on the ground: after it settles it stays where it is (it
// neither sinks in nor slides off nor creeps), the two never cross, and what motion is left dies
// away. (Two soft balls stacked rock gently about their contact, a rigid rotation that the
// deformation damping leaves alone: measured, a top vertex at 0.16 m/s after 3 s, its energy
// falling by about a fifth per 0.35 s cycle, through friction. Jitter, the contact's impulses and
// gravity bouncing a vertex step after step, would not die away.)
// Under every integrator: RK4 ends its step with an end velocity that differs from the path's by
// about a dt / 2, which the contact must settle too (BodyContacts::settleEndVelocities).
class RestingOnABall : public ::testing::TestWithParam<Integrator> {};

TEST_P(RestingOnABall, StaysAtRest) {
  Model model;
  // Centred (a ball on a ball is an unstable balance; flattened at the contact and with friction,
  // a soft one holds there).
  BodyDesc lowerBall = ball("lower", {0.0, 0.52, 0.0}, {}), upperBall = ball("upper", {0.0, 1.6, 0.0}, {});
  lowerBall.contactFriction = upperBall.contactFriction = 1.0;
  // Damped well enough to settle within the test's 3 s: the upper ball bounces on the lower
  // one as on a spring (both soft), and with the default decay (0.1 s) that takes over 5 s.
  lowerBall.deformationDecay = upperBall.deformationDecay = 0.02;
  addBody(model, lowerBall);
  addBody(model, upperBall);
  PlaneCollider ground;
  ground.point = {};
  ground.normal = {0.0, 1.0, 0.0};
  ground.material = {0.0, 0.5};
  model.colliders.planes.push_back(ground);
  const double dt = 5e-4;
  model.colliders.restingSpeed = 4.0 * 9.81 * dt;
  World world(std::move(model), GetParam(), dt);
  for (int s = 0; s < 6000; ++s) {  // 3 s: the drop, the squash, settling
    world.step();
    if (s % 50 == 0) {
      ASSERT_TRUE(findIntersections(world.model(), world.positions(), 1).empty()) << "step " << s;
    }
  }
  const Vec3 lower = measureBody(world, 0).centroid, upper = measureBody(world, 1).centroid;
  EXPECT_GT(upper.y - lower.y, 0.9);  // on top, not sunk in (radii 0.5 each, flattened a little)
  const auto kinetic = [&] { return measureBody(world, 0).kinetic + measureBody(world, 1).kinetic; };
  // Over the first and the last 0.35 s (a cycle of the rocking): the most kinetic energy, and the
  // upper ball's mean centroid.
  double first = 0.0, last = 0.0;
  Vec3 firstMean, lastMean;
  for (int s = 0; s < 2100; ++s) {  // 1.05 s more
    world.step();
    if (s < 700) first = std::max(first, kinetic()), firstMean += measureBody(world, 1).centroid / 700.0;
    if (s >= 1400) last = std::max(last, kinetic()), lastMean += measureBody(world, 1).centroid / 700.0;
    if (s % 50 == 0) {
      ASSERT_TRUE(findIntersections(world.model(), world.positions(), 1).empty()) << "step " << s;
    }
  }
  EXPECT_LT(last, 0.7 * first) << "the motion at rest does not die away";
  EXPECT_LT(length(lastMean - firstMean), 1e-3) << "the upper ball creeps";
  EXPECT_LT(length(measureBody(world, 0).centroid - lower), 5e-3);
  EXPECT_GT(measureBody(world, 1).centroid.y - measureBody(world, 0).centroid.y, 0.9);
}

INSTANTIATE_TEST_SUITE_P(BodyContact, RestingOnABall,
                         ::testing::Values(Integrator::SymplecticEuler, Integrator::RK4, Integrator::VelocityVerlet),
                         [](const auto& p) { return std::string(integratorName(p.param)); });

// A small cube set down 2.4 cm inside the contact thickness of a pinned slab tilted by 20 degrees
// (friction 1, which holds it): the push that separates them moves the cube's bottom no faster
// than the overlap in 0.05 s, so the cube follows without being crushed. Pushed by a tenth of
// the overlap per 0.25 ms step alone, it gained 2 J (of 1.8) in 33 ms, which the monitor stopped
// as an instability. It then stays where it settled.
TEST(BodyContact, ABodyStartingInsideTheThicknessSettlesOutOfItGently) {
  const SceneDesc scene = parseScene(R"(
[scene]
duration = 1.0
[environment]
gravity = [0.0, -9.81, 0.0]
[[body]]
name = "cube"
shape = "cube"
size = 0.5
subdivisions = 2
position = [0.0, 0.78, 0.0]
rotation = [0.0, 0.0, 20.0]
mass = 1.0
contact_friction = 1.0
[[body]]
name = "slab"
shape = "cube"
size = 2.0
subdivisions = 2
position = [0.0, -0.6, 0.0]
rotation = [0.0, 0.0, 20.0]
pin = ["all"]
contact_friction = 1.0
)",
                                     "slab.toml");
  World world(buildModel(scene), Integrator::RK4, 0.25e-3);
  Monitor monitor(world);
  const auto centroid = [&] { return measureBody(world, 0).centroid; };
  Vec3 settled;
  for (int s = 1; s <= 8000; ++s) {  // 2 s
    world.step();
    if (s % 40 == 0) {
      const std::optional<Failure> failure = monitor.check(world);
      ASSERT_FALSE(failure) << failure->message;
    }
    if (s == 4000) settled = centroid();
  }
  EXPECT_LT(length(centroid() - settled), 1e-4) << "it slides or creeps after settling";
}

// A thin plate's rim entering a ball from the side, between its vertices: no vertex of the ball
// ever crosses the plate (they pass above and below it), so the colliders' vertex test cannot
// see it; the edge test of the contact stage does. With contact the rim never enters the ball's
// surface; without (a ghost body), it slices through.
TEST(BodyContact, APlateRimEnteringBetweenVerticesIsCaught) {
  for (bool contact : {false, true}) {
    Model model;
    model.gravity = {};
    BodyDesc desc = ball("ball", {-0.7, 0.0, 0.0}, {5.0, 0.0, 0.0}, contact);
    desc.mesh = moved(makeIcosphere(0.5, 1), {-0.7, 0.0, 0.0});  // 42 vertices: wide gaps between them
    addBody(model, desc);
    TriangleCollider plate;
    plate.name = "plate";
    const double y = 0.0123;  // between the ball's vertex rows, none in the plate's plane
    plate.mesh.positions = {{0.0, y, -2.0}, {0.0, y, 2.0}, {3.0, y, 2.0}, {3.0, y, -2.0}};
    plate.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    plate.material = {0.0, 0.0};
    model.colliders.meshes.push_back(plate);
    World world(std::move(model), Integrator::RK4, kStep);
    EXPECT_EQ(world.bodyContacts() != nullptr, contact);
    const Vec3 rimA = {0.0, y, -2.0}, rimB = {0.0, y, 2.0};
    bool entered = false;
    for (int s = 0; s < 1000 && !entered; ++s) {  // 0.2 s: 1 m of travel
      world.step();
      for (uint32_t f = 0; f < world.model().faces.size() && !entered; ++f) {
        const Triangle& t = world.model().faces[f];
        Vec3 at;
        entered = segmentCrossesTriangle(rimA, rimB, world.positions()[t[0]], world.positions()[t[1]],
                                         world.positions()[t[2]], at);
      }
    }
    EXPECT_EQ(entered, !contact) << (contact ? "the rim entered the ball" : "the rim should slice through a ghost");
    if (contact) {
      EXPECT_GT(world.bodyContacts()->sinceStart().contacts, 0u);
      EXPECT_LT(measureBody(world, 0).momentum.x, 0.0);  // stopped and pushed back by its own elasticity
    }
  }
}

// A ball resting in a slot between two plates, on their two rims: it settles and stays calm.
// (The rims' edge contact and the plates' own vertex stage must not fight: with the contact's
// push inside the thickness applied against the rims, a ball on a box's rim vibrated with 7 J of
// kinetic energy in scenes/pile.toml while its centroid stood still.)
TEST(BodyContact, ABallRestingOnTwoPlateRimsStaysCalm) {
  Model model;
  BodyDesc desc = ball("ball", {0.0, 0.45, 0.0}, {});
  desc.deformationDecay = 0.03;
  addBody(model, desc);
  TriangleCollider plates;
  plates.name = "plates";
  plates.mesh.positions = {{-2.0, 0.0, -1.0}, {-2.0, 0.0, 1.0}, {-0.2, 0.0, 1.0}, {-0.2, 0.0, -1.0},
                           {0.2, 0.0, -1.0},  {0.2, 0.0, 1.0},  {2.0, 0.0, 1.0},  {2.0, 0.0, -1.0}};
  plates.mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  plates.material = {0.0, 0.8};
  model.colliders.meshes.push_back(plates);
  const double dt = 2e-4;
  model.colliders.restingSpeed = 4.0 * 9.81 * dt;
  World world(std::move(model), Integrator::SymplecticEuler, dt);
  for (int s = 0; s < 10000; ++s) world.step();  // 2 s: drop onto the rims and settle
  double most = 0.0;
  for (int s = 0; s < 2500; ++s) {  // 0.5 s more
    world.step();
    most = std::max(most, measureBody(world, 0).kinetic);
  }
  EXPECT_GT(world.bodyContacts()->sinceStart().contacts, 0u);
  EXPECT_GT(measureBody(world, 0).centroid.y, 0.2);  // held by the rims (the slot is 0.4 m wide)
  // Measured: at most 7.4e-6 J over the half second; with the push against the rims 1.2e-4 J.
  EXPECT_LT(most, 3e-5) << "the ball on the rims vibrates";
}

// The fail-safe alone (no impulse passes): vertices in an approaching contact stop for the step,
// so nothing crosses, and each group of stopped vertices shares its momentum, so the total is
// kept.
TEST(BodyContact, FailSafeAloneKeepsBodiesApartAndMomentum) {
  World world(twoBalls(true), Integrator::RK4, kStep);
  world.bodyContacts()->setImpulsePasses(0);
  const Vec3 p0 = momentum(world);
  uint64_t stopped = 0;
  for (int s = 0; s < 1500; ++s) {
    world.step();
    stopped += world.bodyContacts()->lastStep().stopped;
    if (s % 10 == 0) {
      ASSERT_TRUE(findIntersections(world.model(), world.positions(), 1).empty()) << "crossed at step " << s;
    }
  }
  EXPECT_GT(stopped, 0u);
  const Vec3 p1 = momentum(world);
  EXPECT_NEAR(p1.x, p0.x, 1e-9);
  EXPECT_NEAR(p1.y, p0.y, 1e-9);
  EXPECT_NEAR(p1.z, p0.z, 1e-9);
}

// Two balls side by side whose vertices fly about at 10 km/s (a blown-up state): every
// primitive's swept box overlaps most of the other ball's. The search gives up after
// kMaxCandidatesPerPrimitive candidates per primitive instead of testing them all (quadratic in
// the bodies' size), counts the overflow, and the monitor stops the run naming it.
TEST(BodyContact, AnOverflowingSearchIsReportedNotSkippedSilently) {
  Model model;
  model.gravity = {};
  addBody(model, ball("a", {-0.55, 0.0, 0.0}, {}));
  addBody(model, ball("b", {0.55, 0.0, 0.0}, {}));
  uint64_t state = 12345;
  const auto next = [&] {  // a fixed sequence in [-1, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1.0p-52 - 1.0;
  };
  for (Vec3& v : model.initialVelocity) v = Vec3{next(), next(), next()} * 1e4;
  World world(std::move(model), Integrator::SymplecticEuler, kStep);
  Monitor monitor(world);
  world.step();
  EXPECT_EQ(world.bodyContacts()->lastStep().overflows, 1u);
  const std::optional<Failure> failure = monitor.check(world);
  ASSERT_TRUE(failure.has_value());
  EXPECT_NE(failure->message.find("contact search"), std::string::npos) << failure->message;
  EXPECT_NE(failure->message.find("'b'"), std::string::npos) << failure->message;
}

// A scene whose bodies start crossing is refused at load, naming both bodies and their faces.
TEST(BodyContact, BodiesThatStartCrossingAreRefused) {
  SimulationDesc desc;
  desc.path = "two.toml";
  desc.bodies = {ball("a", {}, {}), ball("b", {0.8, 0.0, 0.0}, {})};
  desc.bodies[0].source = "two.toml:3:1: [[body]] #1";
  try {
    buildModel(desc);
    FAIL() << "crossing bodies were accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("two.toml:3:1"), std::string::npos) << what;
    EXPECT_NE(what.find("body 'a' starts crossing body 'b'"), std::string::npos) << what;
  }
  desc.bodies[1].contact = false;  // a ghost may start anywhere
  EXPECT_NO_THROW(buildModel(desc));
}

// The scene keys: read into the body, and a bad value names its file, line and key.
TEST(BodyContact, SceneKeys) {
  const std::string body = "[[body]]\nshape = \"icosphere\"\nsubdivisions = 1\n";
  const SceneDesc scene = parseScene(body +
                                         "contact = false\nself_contact = true\ncontact_thickness = 0.02\n"
                                         "contact_friction = 0.7\ncontact_restitution = 0.4\n",
                                     "keys.toml");
  EXPECT_FALSE(scene.bodies[0].contact);
  EXPECT_TRUE(scene.bodies[0].selfContact);
  EXPECT_EQ(scene.bodies[0].contactThickness, 0.02);
  EXPECT_EQ(scene.bodies[0].contactFriction, 0.7);
  EXPECT_EQ(scene.bodies[0].contactRestitution, 0.4);
  const SceneDesc plain = parseScene(body, "plain.toml");
  EXPECT_TRUE(plain.bodies[0].contact);
  EXPECT_FALSE(plain.bodies[0].selfContact);
  EXPECT_EQ(plain.bodies[0].contactThickness, 0.0);  // automatic
  for (const std::string& bad : {std::string("contact_friction = -1\n"), std::string("contact_thickness = 0\n"),
                                 std::string("contact_restitution = 1.5\n"), std::string("self_contact = 3\n")}) {
    try {
      parseScene(body + bad, "bad.toml");
      FAIL() << "accepted " << bad;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("bad.toml:4"), std::string::npos) << what;
      EXPECT_NE(what.find(bad.substr(0, bad.find(' '))), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace springy

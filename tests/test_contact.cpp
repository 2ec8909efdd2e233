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

// The same bits on one and two threads (the contact stage runs on one thread, in a fixed order).
TEST(BodyContact, BitIdenticalOnOneAndTwoThreads) {
  uint64_t hashes[2];
  for (unsigned threads : {1u, 2u}) {
    World world(twoBalls(true), Integrator::RK4, kStep);
    world.setThreads(threads, 0);
    for (int s = 0; s < 1200; ++s) world.step();
    hashes[threads - 1] = stateHash(world);
  }
  EXPECT_EQ(hashes[0], hashes[1]);
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
                                         "contact_friction = 0.7\n",
                                     "keys.toml");
  EXPECT_FALSE(scene.bodies[0].contact);
  EXPECT_TRUE(scene.bodies[0].selfContact);
  EXPECT_EQ(scene.bodies[0].contactThickness, 0.02);
  EXPECT_EQ(scene.bodies[0].contactFriction, 0.7);
  const SceneDesc plain = parseScene(body, "plain.toml");
  EXPECT_TRUE(plain.bodies[0].contact);
  EXPECT_FALSE(plain.bodies[0].selfContact);
  EXPECT_EQ(plain.bodies[0].contactThickness, 0.0);  // automatic
  for (const std::string& bad : {std::string("contact_friction = -1\n"), std::string("contact_thickness = 0\n"),
                                 std::string("self_contact = 3\n")}) {
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

// The showcase scenes: each tells a story, and this file checks it happens. Scenes are run
// from their files exactly as `springy check` and `springy render` load them.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <cmath>
#include <limits>

#include "scene/scene.h"
#include "sim/contact.h"
#include "sim/contact_geometry.h"
#include "sim/diagnostics.h"
#include "sim/intersections.h"
#include "sim/monitor.h"
#include "sim/stability.h"

namespace springy {
namespace {

constexpr double kNotYet = 1e9;  // a time not reached

std::string scenePath(const std::string& name) { return std::string(SPRINGY_SOURCE_DIR) + "/scenes/" + name + ".toml"; }

struct SceneRun {
  SceneDesc scene;
  World world;
  Monitor monitor;
  RestWatch rest;
  explicit SceneRun(const std::string& name)
      : scene(advised(loadScene(scenePath(name)))),
        world(buildModel(scene), scene.integrator, stepSize(scene)),
        monitor(world) {}
  // A scene that gives no step runs at the advisor's, as springy check and render run it (their run
  // is its try, and more substeps are tried only if it fails; on these scenes it passes at once).
  static SceneDesc advised(SceneDesc scene) {
    if (!scene.stepGiven) adviseSubsteps(scene);
    return scene;
  }
  // Advances to time t, checking stability at every frame (1/30 s); fails the test on a failure.
  void advance(double t, const std::function<void()>& perFrame = {}) {
    while (world.time() < t - 0.5 * world.dt()) {
      const double frameEnd = std::min(t, world.time() + 1.0 / 30.0);
      while (world.time() < frameEnd - 0.5 * world.dt()) world.step();
      const std::optional<Failure> failure = monitor.check(world);
      ASSERT_FALSE(failure) << failure->message;
      if (perFrame) perFrame();
    }
  }
  // Runs to the scene's end, watching its last second for rest (RestWatch, as `springy check
  // --end-at-rest` does).
  void advanceToEnd(const std::function<void()>& perFrame = {}) {
    advance(scene.duration - RestWatch::kWindow, perFrame);
    rest.add(world.positions());
    advance(scene.duration, [&] {
      rest.add(world.positions());
      if (perFrame) perFrame();
    });
  }
  // At rest over the last second (after advanceToEnd); names the vertex that moved most if not.
  ::testing::AssertionResult restsAtEnd(uint32_t b) const {
    const BodyInfo& info = world.model().bodies[b];
    if (rest.atRest(info)) return ::testing::AssertionSuccess();
    const auto [moved, vertex] = rest.largestMove(info);
    return ::testing::AssertionFailure() << "body '" << info.name << "' not at rest at " << world.time() << " s: model vertex "
                                         << vertex << " moved " << moved << " m in the last second";
  }
  BodyMeasures body(uint32_t b) const { return measureBody(world, b); }
  double height(uint32_t b) const {  // vertical extent of a body
    const BodyInfo& info = world.model().bodies[b];
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      lo = std::min(lo, world.positions()[i].y);
      hi = std::max(hi, world.positions()[i].y);
    }
    return hi - lo;
  }
  double lowest(uint32_t b) const {
    const BodyInfo& info = world.model().bodies[b];
    double lo = std::numeric_limits<double>::infinity();
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) lo = std::min(lo, world.positions()[i].y);
    return lo;
  }
};

TEST(Scenes, SingleSphereBouncesThenRestsOnTheGroundKeepingItsVolume) {
  SceneRun run("single_sphere");
  const double radius = 6.0;
  run.advanceToEnd();
  const BodyRecord& r = run.monitor.records()[0];
  const BodyMeasures m = run.body(0);
  EXPECT_GT(r.minVolumeRatio, 0.8);                    // squashed on impact, not crushed
  EXPECT_LT(r.minVolumeRatio, 0.95);                   // but squashed: the ball is soft
  EXPECT_GT(m.volume / run.world.model().bodies[0].restVolume, 0.95);  // and back
  EXPECT_TRUE(run.restsAtEnd(0));
  EXPECT_NEAR(run.lowest(0), 0.0, 1e-3);               // on the ground
  EXPECT_GT(m.centroid.y, 0.75 * radius);              // sagging a little under its weight
  EXPECT_LT(m.centroid.y, radius);
}

TEST(Scenes, ThreeSpheresSquashAndBounceByDifferentAmounts) {
  SceneRun run("spheres");
  std::array<double, 3> bounce{0, 0, 0};  // highest centroid after the first impact
  std::array<bool, 3> landed{false, false, false};
  run.advance(5.0, [&] {
    for (uint32_t b = 0; b < 3; ++b) {
      landed[b] = landed[b] || run.lowest(b) < 0.01;
      if (landed[b]) bounce[b] = std::max(bounce[b], run.body(b).centroid.y);
    }
  });
  // Volume lost at the deepest squash: the soft ball (P_theta 0.8 s) gives most, the firm one
  // (P_theta 0.34 s, T_theta 0.5 s) least; and the firmer the ball, the higher it bounces.
  const auto& r = run.monitor.records();
  EXPECT_LT(r[0].minVolumeRatio, r[1].minVolumeRatio - 0.02);
  EXPECT_LT(r[1].minVolumeRatio, r[2].minVolumeRatio - 0.03);
  EXPECT_LT(bounce[0], bounce[1] - 1.0);
  EXPECT_LT(bounce[1], bounce[2] - 1.0);
  run.advanceToEnd();
  for (uint32_t b = 0; b < 3; ++b) {
    EXPECT_TRUE(run.restsAtEnd(b));
    EXPECT_LT(run.lowest(b), 1e-3);  // on the ground
  }
}

TEST(Scenes, HangingSphereKeepsItsPolePinnedAndSettlesBelowRest) {
  SceneRun run("fixed_single_sphere");
  const uint32_t top = run.world.model().bodies[0].modelVertex[0];  // the mesh's vertex 0, the pole
  ASSERT_EQ(run.world.model().pinned, (std::vector<uint32_t>{top}));
  const Vec3 pole = run.world.positions()[top];
  EXPECT_EQ(pole, (Vec3{0.0, 22.0, 0.0}));
  run.advanceToEnd();
  EXPECT_EQ(run.world.positions()[top], pole);  // exactly: a pinned vertex never moves
  EXPECT_TRUE(run.restsAtEnd(0));                // hanging still
  const BodyMeasures m = run.body(0);
  EXPECT_LT(m.centroid.y, 16.0 - 0.5);  // stretched under its own weight
  EXPECT_GT(m.centroid.y, 10.0);
  EXPECT_GT(m.volume / run.world.model().bodies[0].restVolume, 0.95);
}

TEST(Scenes, RampBallTouchesThePlatesInTurnAndEndsAtRestOnTheGround) {
  SceneRun run("ramp");
  const TriangleCollider& plates = run.world.model().colliders.meshes.at(0);
  ASSERT_EQ(plates.mesh.triangles.size(), 8u);  // four quads
  // Distance from a point to plate k (two triangles 2k, 2k+1), via its plane and extent.
  auto nearPlate = [&](const Vec3& p, int k) {
    const Triangle& t = plates.mesh.triangles[static_cast<std::size_t>(2 * k)];
    const Vec3 a = plates.mesh.positions[t[0]], b = plates.mesh.positions[t[1]], c = plates.mesh.positions[t[2]];
    const Vec3 n = normalized(cross(b - a, c - a));
    const double lo = std::min(a.x, b.x), hi = std::max(a.x, b.x);
    return std::fabs(dot(p - a, n)) < 0.05 && p.x >= lo && p.x <= hi;
  };
  std::array<double, 4> firstTouch{-1, -1, -1, -1};
  double landed = -1;
  run.advanceToEnd([&] {
    for (const Vec3& p : run.world.positions()) {
      for (int k = 0; k < 4; ++k) {
        if (firstTouch[static_cast<std::size_t>(k)] < 0 && nearPlate(p, k)) firstTouch[static_cast<std::size_t>(k)] = run.world.time();
      }
      if (landed < 0 && p.y < -40.0 + 0.05) landed = run.world.time();
    }
  });
  for (int k = 0; k < 4; ++k) EXPECT_GE(firstTouch[static_cast<std::size_t>(k)], 0.0) << "plate " << k << " never touched";
  for (int k = 0; k < 3; ++k) EXPECT_LT(firstTouch[static_cast<std::size_t>(k)], firstTouch[static_cast<std::size_t>(k + 1)]);
  EXPECT_GT(landed, firstTouch[3]);
  EXPECT_NEAR(run.lowest(0), -40.0, 0.05);  // on the ground at the end
  EXPECT_LT(std::fabs(run.body(0).centroid.x), 30.0);  // still in the camera's view
  EXPECT_TRUE(run.restsAtEnd(0));  // the soft ground's rolling resistance stopped it
}

TEST(Scenes, LegacyCubeKeepsItsVolume) {
  SceneRun run("cube");
  ASSERT_EQ(run.world.model().struts.size(), 28u);
  ASSERT_TRUE(run.world.model().hinges.empty());
  run.advanceToEnd();
  const BodyRecord& r = run.monitor.records()[0];
  EXPECT_GT(r.minVolumeRatio, 0.85);
  EXPECT_LT(r.maxVolumeRatio, 1.15);
  EXPECT_NEAR(run.body(0).volume / run.world.model().bodies[0].restVolume, 1.0, 0.02);
  EXPECT_LT(run.lowest(0), 0.05);  // on the ground
  EXPECT_TRUE(run.restsAtEnd(0));
}

TEST(Scenes, JellyWobblesAndRecoversItsShape) {
  SceneRun run("jelly");
  const BodyMeasures start = run.body(0);
  run.advanceToEnd();
  const BodyRecord& r = run.monitor.records()[0];
  const BodyMeasures end = run.body(0);
  EXPECT_LT(r.minVolumeRatio, 0.97);  // it squashes on impact
  EXPECT_GT(r.minVolumeRatio, 0.85);
  EXPECT_GT(end.volume / run.world.model().bodies[0].restVolume, 0.95);
  EXPECT_GT(start.gravitational - end.gravitational, 500.0);  // 6 kg dropped about 10 m
  EXPECT_TRUE(run.restsAtEnd(0));  // the wobble has died out
  EXPECT_LT(run.lowest(0), 1e-3);
}

TEST(Scenes, FullBunnyLandsAndKeepsItsShape) {
  // 1839 vertices: through the impact (at about 1.4 s) and the first rebound.
  SceneRun run("bunny");
  EXPECT_EQ(run.world.model().bodies[0].vertexCount, 1839u);
  const double startHeight = run.height(0);
  run.advance(3.0);
  const BodyRecord& r = run.monitor.records()[0];
  EXPECT_LT(run.lowest(0), 1.0);  // down on the ground (it fell from about 10)
  EXPECT_GT(r.minVolumeRatio, 0.85);  // the scene file's stated lowest volume
  EXPECT_GT(run.body(0).volume / run.world.model().bodies[0].restVolume, 0.95);
  EXPECT_GT(run.height(0), 0.9 * startHeight);  // ears up again
}

// The gap between two bodies: the least distance from a vertex of one to a face of the other.
double gapBetween(const World& world, uint32_t a, uint32_t b) {
  const Model& model = world.model();
  const std::vector<Vec3>& x = world.positions();
  double gap = std::numeric_limits<double>::infinity();
  for (const auto& [v, f] : {std::pair{a, b}, std::pair{b, a}}) {
    const BodyInfo &vi = model.bodies[v], &fi = model.bodies[f];
    for (uint32_t i = vi.firstVertex; i < vi.firstVertex + vi.vertexCount; ++i) {
      for (uint32_t k = fi.firstFace; k < fi.firstFace + fi.faceCount; ++k) {
        const Triangle& t = model.faces[k];
        gap = std::min(gap, std::sqrt(closestPointTriangle(x[i], x[t[0]], x[t[1]], x[t[2]]).distanceSquared));
      }
    }
  }
  return gap;
}

TEST(Scenes, SampleBodiesMeetThePlatesThePlaneAndEachOther) {
  // The cube and the icosphere fall onto the two tilted plates, the tetrahedron onto the plane;
  // the bunny falls onto the tetrahedron and is thrown off it onto the plane.
  SceneRun run("sample");
  const TriangleCollider& plates = run.world.model().colliders.meshes.at(0);
  ASSERT_EQ(plates.mesh.triangles.size(), 4u);  // two quads
  auto onPlate = [&](uint32_t b, int k) {  // a vertex of body b within 5 cm of plate k, inside its x extent
    const Triangle& t = plates.mesh.triangles[static_cast<std::size_t>(2 * k)];
    const Vec3 a = plates.mesh.positions[t[0]], p1 = plates.mesh.positions[t[1]], c = plates.mesh.positions[t[2]];
    const Vec3 n = normalized(cross(p1 - a, c - a));
    const double lo = std::min({a.x, p1.x, c.x}), hi = std::max({a.x, p1.x, c.x});
    const BodyInfo& info = run.world.model().bodies[b];
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      const Vec3& x = run.world.positions()[i];
      if (std::fabs(dot(x - a, n)) < 0.05 && x.x >= lo && x.x <= hi) return true;
    }
    return false;
  };
  std::array<bool, 4> plate{}, ground{};
  // Within 5 cm of the pair's contact thickness, which keeps them apart.
  const BodyContacts* contacts = run.world.bodyContacts();
  ASSERT_NE(contacts, nullptr);
  const auto touching = [&](uint32_t a, uint32_t b) {
    return gapBetween(run.world, a, b) < 0.5 * (contacts->thickness(a) + contacts->thickness(b)) + 0.05;
  };
  double bunnyOnTetrahedron = kNotYet;  // the first time they touch
  int frame = 0;
  run.advance(6.0, [&] {
    for (uint32_t b = 0; b < 4; ++b) {
      plate[b] = plate[b] || onPlate(b, b == 0 ? 0 : 1);
      ground[b] = ground[b] || run.lowest(b) < 0.05;
    }
    if (++frame % 3 != 0) return;  // every 0.1 s
    const double t = run.world.time();
    if (bunnyOnTetrahedron == kNotYet && touching(3, 2)) bunnyOnTetrahedron = t;
  });
  EXPECT_TRUE(plate[0]) << "the cube never touched the first plate";
  EXPECT_TRUE(plate[1]) << "the icosphere never touched the second plate";
  EXPECT_TRUE(ground[2]) << "the tetrahedron never reached the plane";
  EXPECT_TRUE(ground[3]) << "the bunny never reached the plane";
  EXPECT_LT(bunnyOnTetrahedron, 3.0) << "the bunny did not land on the tetrahedron";
  for (uint32_t b = 0; b < 4; ++b) EXPECT_GT(run.monitor.records()[b].minVolumeRatio, 0.7) << b;
}

// The flag, held along its pole side, streams out downwind in the gusts and never folds through
// itself (it has no self contact: the audit looks at its faces here). 3 s of its 20.
TEST(Scenes, FlagStreamsFromItsPoleAndNeverFoldsThroughItself) {
  SceneRun run("flag");
  const Model& model = run.world.model();
  EXPECT_TRUE(model.bodies[0].open);
  EXPECT_NE(std::find(run.world.forceStages().begin(), run.world.forceStages().end(), ForceStage::Wind),
            run.world.forceStages().end());
  ASSERT_EQ(model.pinned.size(), 21u);  // the whole edge at the pole
  for (uint32_t i : model.pinned) EXPECT_EQ(model.restPosition[i].x, 0.0);
  Model audit = model;
  audit.bodies[0].selfContact = true;
  double farthest = 0.0;
  run.advance(3.0, [&] {
    const std::vector<Intersection> crossing = findIntersections(audit, run.world.positions(), 1);
    ASSERT_TRUE(crossing.empty()) << "the flag crosses itself at " << run.world.time() << " s";
    farthest = std::min(farthest, run.body(0).centroid.x);
  });
  for (uint32_t i : model.pinned) EXPECT_EQ(run.world.positions()[i], model.restPosition[i]);
  // Streaming downwind (-x) from the pole: in still air it hangs by the pole (centroid x 0.06 at 3 s).
  EXPECT_LT(run.body(0).centroid.x, -0.5);
  EXPECT_GT(run.body(0).centroid.y, 1.8);  // and not down on the ground
  EXPECT_LT(farthest, -0.6);
}

// The cloth lands on the pinned ball and drapes over it: held up by the ball's top, hanging
// down its sides, never inside it, and never through itself or the ball (the monitor's audit at
// every frame, the cloth's self contact included). The first half second: the whole run to rest
// (5 s) takes minutes.
TEST(Scenes, DrapeCoversTheBallWithoutCrossing) {
  SceneRun run("drape");
  const Model& model = run.world.model();
  ASSERT_EQ(model.bodies.size(), 2u);
  ASSERT_TRUE(model.bodies[0].open);
  ASSERT_TRUE(model.bodies[0].selfContact);
  const BodyInfo& cloth = model.bodies[0];
  const Vec3 centre{0.0, 0.3, 0.0};
  const double radius = 0.3;
  double closest = 1.0;  // of any cloth vertex to the ball's centre, over the run
  run.advance(0.5, [&] {
    for (uint32_t i = cloth.firstVertex; i < cloth.firstVertex + cloth.vertexCount; ++i) {
      closest = std::min(closest, length(run.world.positions()[i] - centre));
    }
  });
  double highest = 0.0, lowest = 1.0;
  for (uint32_t i = cloth.firstVertex; i < cloth.firstVertex + cloth.vertexCount; ++i) {
    highest = std::max(highest, run.world.positions()[i].y);
    lowest = std::min(lowest, run.world.positions()[i].y);
  }
  // The icosphere's faces lie inside its circumscribed sphere by up to 1.2% of the radius.
  EXPECT_GT(closest, 0.98 * radius) << "a cloth vertex went into the ball";
  EXPECT_GT(highest, 2.0 * radius) << "not held up by the ball's top";
  // Over it, not lying flat on its top: most of the sheet is below the top (its folds stand up).
  EXPECT_LT(run.body(0).centroid.y, 2.0 * radius);
  EXPECT_LT(lowest, radius) << "not hanging down the ball's sides";
  ASSERT_NE(run.world.bodyContacts(), nullptr);
  EXPECT_GT(run.world.bodyContacts()->sinceStart().contacts, 0u);
  EXPECT_EQ(run.world.bodyContacts()->sinceStart().overflows, 0u);
}

TEST(Scenes, LightBunnyStaysStableAndKeepsItsShape) {
  SceneRun run("bunny_light");
  EXPECT_EQ(run.world.model().bodies[0].vertexCount, 500u);
  run.advance(4.0);
  EXPECT_GT(run.body(0).volume / run.world.model().bodies[0].restVolume, 0.9);
}

// Twenty-four balls poured into the box: none leaves it (walls 1.4 m high), none passes
// through another or through a wall's rim (the monitor's audit at every frame), and they heap
// up: more balls than fit on the box's floor (4 x 2 of them) are held up by the others.
TEST(Scenes, PileBallsHeapUpInTheBoxWithoutCrossing) {
  SceneRun run("pile");
  run.advance(1.6);  // the last of them lands at about 1.2 s
  const uint32_t n = static_cast<uint32_t>(run.world.model().bodies.size());
  ASSERT_EQ(n, 24u);
  uint32_t raised = 0;
  for (uint32_t b = 0; b < n; ++b) {
    const Vec3 c = run.body(b).centroid;
    EXPECT_LT(std::fabs(c.x), 1.0) << run.world.model().bodies[b].name;
    EXPECT_LT(std::fabs(c.z), 0.7) << run.world.model().bodies[b].name;
    if (run.lowest(b) > 0.1) ++raised;  // resting on other balls, not on the floor
  }
  EXPECT_GE(raised, 24u - 8u);
  ASSERT_NE(run.world.bodyContacts(), nullptr);
  EXPECT_GT(run.world.bodyContacts()->sinceStart().contacts, 0u);
  EXPECT_EQ(run.world.bodyContacts()->sinceStart().overflows, 0u);
}

// The bunny lands on the bed of nine balls and is held up by them; the balls stay in the tray,
// and nothing passes through anything (the monitor's audit at every frame).
TEST(Scenes, StackBunnyLandsOnTheBedOfBallsWhichStaysInTheTray) {
  SceneRun run("stack");
  double held = 0.0;  // time the bunny spent low enough to touch the balls' tops, above the floor
  run.advance(1.5, [&] {  // it lands at about 0.5 s
    const double low = run.lowest(0);
    if (low < 0.7 && low > 0.3) held += 1.0 / 30.0;
  });
  EXPECT_GT(held, 0.3) << "the bunny was not held up by the balls";
  for (uint32_t b = 1; b <= 9; ++b) {
    const Vec3 c = run.body(b).centroid;
    EXPECT_LT(std::max(std::fabs(c.x), std::fabs(c.z)), 0.95 - 0.25) << run.world.model().bodies[b].name;
    EXPECT_LT(c.y, 0.35) << run.world.model().bodies[b].name << " was pushed out of the bed";
  }
  ASSERT_NE(run.world.bodyContacts(), nullptr);
  EXPECT_GT(run.world.bodyContacts()->sinceStart().contacts, 0u);
}

// Press: squeezed by the plate to half its height (it bulges sideways), then released: back over
// 90% of its volume, round again and at rest; no vertex ever above the plate's underside.
TEST(Scenes, PressSqueezesTheBallToHalfItsHeightAndItSpringsBack) {
  SceneRun run("press");
  const TriangleCollider& plate = run.scene.triangleColliders[0];
  double squeezed = 1e9;
  run.advance(2.2, [&] {
    const double underside = 1.2 + plate.motion.translation(run.world.time()).y;
    for (const Vec3& x : run.world.positions()) ASSERT_LE(x.y, underside + 1e-9) << run.world.time();
    squeezed = std::min(squeezed, run.height(0));
  });
  EXPECT_NEAR(squeezed, 0.5, 0.01);  // the plate's lowest: 0.5 m over the ground
  run.advanceToEnd();
  const BodyRecord& r = run.monitor.records()[0];
  EXPECT_LT(r.minVolumeRatio, 0.9);  // squeezed hard
  EXPECT_GT(r.minVolumeRatio, 0.7);
  EXPECT_GT(run.body(0).volume / run.world.model().bodies[0].restVolume, 0.9);  // and back
  EXPECT_NEAR(run.height(0), 1.0, 0.03);  // round again (1 m across), sagging a little
  EXPECT_TRUE(run.restsAtEnd(0));
}

// Shaker: the jelly rides the shaking plate: its lowest vertex on the plate at every frame, its
// volume kept; it creeps along +x (a vibratory conveyor, scenes/shaker.toml) but stays near the
// plate's middle.
TEST(Scenes, ShakerJellyRidesTheShakingPlate) {
  SceneRun run("shaker");
  const Movement& motion = run.scene.triangleColliders[0].motion;
  const Vec3 start = run.body(0).centroid;
  double farthest = 0.0;
  run.advance(run.scene.duration, [&] {
    const Vec3 d = motion.translation(run.world.time());
    if (run.world.time() > 0.5) {
      EXPECT_NEAR(run.lowest(0), d.y, 0.005) << run.world.time();
    }
    const Vec3 c = run.body(0).centroid;
    farthest = std::max(farthest, std::hypot(c.x - d.x - start.x, c.z - d.z - start.z));
  });
  EXPECT_LT(farthest, 0.4);  // relative to the plate: it creeps, far from the rim (1.2 m)
  EXPECT_GT(run.monitor.records()[0].minVolumeRatio, 0.85);
}

// Cape: the pinned edge goes round with the bar; the turn swings the cape out; let go, it flies
// off and comes to rest on the ground.
TEST(Scenes, CapeSwingsOutOnItsTurningBarAndLandsWhenLetGo) {
  SceneRun run("cape");
  const Model& model = run.world.model();
  const Movement& motion = run.scene.bodies[0].pinMotion;
  double outward = 0.0;  // the largest distance of a vertex from the axis
  run.advance(3.9, [&] {
    for (uint32_t i : model.pinned) {
      ASSERT_LT(length(run.world.positions()[i] - motion.pose(run.world.time()).apply(model.restPosition[i])), 1e-9);
    }
    for (const Vec3& x : run.world.positions()) outward = std::max(outward, std::hypot(x.x, x.z));
  });
  EXPECT_GT(outward, 1.2 + 0.3);  // swung out well past the bar's 1.2 m (at rest: 1.3 m at a corner)
  run.advanceToEnd();
  EXPECT_LT(run.lowest(0), 0.01);
  EXPECT_LT(run.height(0), 0.1);  // lying on the ground
  EXPECT_TRUE(run.restsAtEnd(0));
}

}  // namespace
}  // namespace springy

// Cloth: open meshes as bodies (docs/model.md §18). The cloth shape, open surfaces' validation
// and their lack of volume, the scene keys, and the physics: a hanging cloth comes to rest without
// stretching much, a dropped one lies on the ground, wind pushes either side, and a cloth folded
// onto itself with self contact never passes through itself.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "error_of.h"
#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/intersections.h"
#include "mesh/mesh_io.h"
#include "sim/monitor.h"
#include "sim/setup.h"
#include "sim/shapes.h"
#include "sim/stability.h"
#include "sim/world.h"

namespace springy {
namespace {

using test::errorOf;

// Undirected edges with the number of triangles on each.
std::map<std::pair<uint32_t, uint32_t>, int> edgeUses(const TriMesh& mesh) {
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k)
      ++uses[std::minmax(t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)])];
  }
  return uses;
}

Vec3 areaVector(const TriMesh& mesh, const Triangle& t) {
  return cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]) * 0.5;
}

// A cloth body of the default cloth material.
BodyDesc cloth(const std::string& name, TriMesh mesh, double mass = 0.2) {
  BodyDesc desc;
  desc.name = name;
  desc.mesh = std::move(mesh);
  desc.mass = mass;
  desc.material = MaterialModel::Body;
  desc.cloth = true;
  return desc;
}

TriMesh transformed(TriMesh mesh, const std::function<Vec3(const Vec3&)>& f) {
  for (Vec3& p : mesh.positions) p = f(p);
  return mesh;
}

// Half the stability advisor's limit for RK4, the margin `springy` itself takes.
double advisedStep(const Model& model, double horizon) {
  return 0.5 * estimateStability(model, model.restPosition, Integrator::RK4, horizon).dtMax;
}

double kinetic(const World& world) {
  double e = 0.0;
  for (std::size_t i = 0; i < world.model().vertexCount(); ++i) {
    e += 0.5 * world.model().mass[i] * lengthSquared(world.velocities()[i]);
  }
  return e;
}

// ------------------------------------------------------------------------------------------------
// The shape.

TEST(ClothShape, GridCountsBorderOrientationAndArea) {
  for (const auto& [columns, rows] : {std::pair{1, 1}, std::pair{5, 3}, std::pair{40, 40}, std::pair{7, 12}}) {
    const double width = 1.5, depth = 0.8;
    const TriMesh m = makeCloth(width, depth, columns, rows);
    const auto n = static_cast<std::size_t>(columns), k = static_cast<std::size_t>(rows);
    EXPECT_EQ(m.positions.size(), (n + 1) * (k + 1));
    EXPECT_EQ(m.triangles.size(), 2 * n * k);
    // Border edges (one triangle) all round the rectangle, interior ones shared by two.
    std::size_t border = 0;
    for (const auto& [edge, count] : edgeUses(m)) {
      EXPECT_TRUE(count == 1 || count == 2) << edge.first << "-" << edge.second;
      if (count == 1) ++border;
    }
    EXPECT_EQ(border, 2 * (n + k));
    // Every triangle faces +y; the areas sum to width x depth; flat, centred at the origin.
    double area = 0.0;
    for (const Triangle& t : m.triangles) {
      const Vec3 a = areaVector(m, t);
      EXPECT_GT(a.y, 0.0);
      EXPECT_EQ(a.x, 0.0);
      EXPECT_EQ(a.z, 0.0);
      area += length(a);
    }
    EXPECT_NEAR(area, width * depth, 1e-12);
    const Bounds b = boundsOf(m.positions);
    EXPECT_DOUBLE_EQ(b.lo.x, -0.5 * width);
    EXPECT_DOUBLE_EQ(b.hi.x, 0.5 * width);
    EXPECT_DOUBLE_EQ(b.lo.z, -0.5 * depth);
    EXPECT_DOUBLE_EQ(b.hi.z, 0.5 * depth);
    EXPECT_EQ(b.lo.y, 0.0);
    EXPECT_EQ(b.hi.y, 0.0);
    EXPECT_EQ(findManifoldProblem(m, Surface::Open), std::nullopt);
  }
}

TEST(ClothShape, DiagonalsAlternate) {
  // The diagonal of quad (i, j) joins (i, j)-(i+1, j+1) or (i+1, j)-(i, j+1), turning with the
  // parity of i + j: as many of each, and neighbours differ.
  const int n = 6;
  const TriMesh m = makeCloth(1.0, 1.0, n, n);
  const auto uses = edgeUses(m);
  const auto at = [](int i, int j) { return static_cast<uint32_t>(i + (n + 1) * j); };
  int rising = 0, falling = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const bool up = uses.count(std::minmax(at(i, j), at(i + 1, j + 1))) > 0;
      const bool down = uses.count(std::minmax(at(i + 1, j), at(i, j + 1))) > 0;
      EXPECT_NE(up, down) << "quad " << i << ", " << j << " has exactly one diagonal";
      EXPECT_EQ(up, (i + j) % 2 == 0) << "quad " << i << ", " << j;
      (up ? rising : falling) += 1;
    }
  }
  EXPECT_EQ(rising, falling);
}

// ------------------------------------------------------------------------------------------------
// Open surfaces: validation, no volume, no gas.

TEST(OpenSurface, ValidationAllowsBordersAndNamesWhatIsWrong) {
  TriMesh sheet = makeCloth(1.0, 1.0, 2, 2);  // 9 vertices; vertex 4 in the middle
  EXPECT_EQ(findManifoldProblem(sheet, Surface::Open), std::nullopt);
  EXPECT_NE(findManifoldProblem(sheet).value_or("").find("the mesh has a hole"), std::string::npos);
  // A fin: a third triangle on the interior edge (0, 4).
  TriMesh fin = sheet;
  fin.positions.push_back({-0.25, 0.5, -0.25});
  fin.triangles.push_back({0, 4, 9});
  EXPECT_EQ(findManifoldProblem(fin, Surface::Open), "edge (0, 4) is shared by 3 triangles: non-manifold edge");
  // A face wound the other way round.
  TriMesh flipped = sheet;
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_NE(findManifoldProblem(flipped, Surface::Open).value_or("").find("traversed twice in the same direction"),
            std::string::npos);
  // Two sheets touching at one corner (a bow tie): vertex 8 of the first is the second's corner.
  TriMesh bowtie = sheet;
  const TriMesh other = transformed(sheet, [](const Vec3& p) { return p + Vec3{1.0, 0.0, 1.0}; });
  std::vector<uint32_t> index(other.positions.size());
  for (uint32_t i = 0; i < other.positions.size(); ++i) {
    index[i] = i == 0 ? 8u : static_cast<uint32_t>(bowtie.positions.size());
    if (i != 0) bowtie.positions.push_back(other.positions[i]);
  }
  for (const Triangle& t : other.triangles) bowtie.triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
  EXPECT_EQ(findManifoldProblem(bowtie, Surface::Open),
            "vertex 8 joins 2 separate fans of triangles: non-manifold vertex");
  // Two pieces apart.
  TriMesh apart = sheet;
  const TriMesh far = transformed(sheet, [](const Vec3& p) { return p + Vec3{3.0, 0.0, 0.0}; });
  for (const Vec3& p : far.positions) apart.positions.push_back(p);
  for (const Triangle& t : far.triangles) apart.triangles.push_back({t[0] + 9, t[1] + 9, t[2] + 9});
  EXPECT_NE(findManifoldProblem(apart, Surface::Open).value_or("").find("2 separate pieces"), std::string::npos);
  // A zero-area triangle: the middle vertex moved onto the diagonal's far end.
  TriMesh degenerate = sheet;
  degenerate.positions[4] = degenerate.positions[8];
  EXPECT_NE(findManifoldProblem(degenerate, Surface::Open).value_or("").find("has zero area"), std::string::npos);
  // A closed surface is an open surface without border.
  EXPECT_EQ(findManifoldProblem(makeIcosphere(1.0, 1), Surface::Open), std::nullopt);
}

TEST(OpenSurface, HasNoVolumeAndRefusesGasNamingTheBody) {
  Model model;
  BodyDesc open = cloth("sheet", makeCloth(1.0, 1.0, 4, 4));
  open.cloth = false;  // open by its border alone
  addBody(model, open);
  EXPECT_TRUE(model.bodies[0].open);
  EXPECT_EQ(model.bodies[0].restVolume, 0.0);
  // Lifted off the origin, the signed "volume" of the sheet's faces about it would not be 0.
  BodyDesc lifted = cloth("lifted", transformed(makeCloth(1.0, 1.0, 4, 4), [](const Vec3& p) {
                            return p + Vec3{0, 1, 0};
                          }));
  addBody(model, lifted);
  EXPECT_EQ(model.bodies[1].restVolume, 0.0);
  World world(model, Integrator::RK4, 1e-4);
  EXPECT_EQ(measureBody(world, 1).volume, 0.0);
  // A closed ball is not open, and cloth = true makes even a closed mesh an open surface.
  BodyDesc ball = cloth("ball", makeIcosphere(0.5, 1));
  ball.cloth = false;
  addBody(model, ball);
  EXPECT_FALSE(model.bodies[2].open);
  EXPECT_GT(model.bodies[2].restVolume, 0.0);
  ball.cloth = true;
  addBody(model, ball);
  EXPECT_TRUE(model.bodies[3].open);
  EXPECT_EQ(model.bodies[3].restVolume, 0.0);

  // Gas: refused, naming the body and why.
  open.volumePeriod = 0.1;
  std::string message = errorOf([&] {
    Model m;
    addBody(m, open);
  });
  EXPECT_NE(message.find("body 'sheet'"), std::string::npos) << message;
  EXPECT_NE(message.find("volume_period needs a closed mesh, but edge ("), std::string::npos) << message;
  ball.volumePeriod = 0.1;
  message = errorOf([&] {
    Model m;
    addBody(m, ball);
  });
  EXPECT_NE(message.find("body 'ball'"), std::string::npos) << message;
  EXPECT_NE(message.find("it is a cloth"), std::string::npos) << message;
  // From a scene file: the file, line and body.
  message = errorOf([] {
    buildModel(parseScene("[[body]]\nname = \"flag\"\nshape = \"cloth\"\nvolume_period = 0.2\n", "gas.toml"));
  });
  EXPECT_EQ(message.rfind("gas.toml:1:1: [[body]] #1: body 'flag'", 0), 0u) << message;
  EXPECT_NE(message.find("volume_period"), std::string::npos) << message;
}

// The monitor skips the volume of an open body (it has none): a cloth falling onto the ground
// with a required minimum volume does not fail.
TEST(OpenSurface, MonitorSkipsTheVolumeCheck) {
  Model model;
  addBody(model, cloth("sheet", transformed(makeCloth(1.0, 1.0, 6, 6), [](const Vec3& p) {
                         return p + Vec3{0, 0.2, 0};
                       })));
  model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, {}});
  const double dt = advisedStep(model, 1.0);
  World world(model, Integrator::RK4, dt);
  MonitorLimits limits;
  limits.minVolume = 0.9;
  Monitor monitor(world, limits);
  for (int frame = 0; frame < 20; ++frame) {
    for (int s = 0; s < static_cast<int>(std::ceil(0.02 / dt)); ++s) world.step();
    const std::optional<Failure> failure = monitor.check(world);
    ASSERT_FALSE(failure) << failure->message;
  }
  EXPECT_EQ(monitor.records()[0].minVolumeRatio, 1.0);  // never measured
}

// ------------------------------------------------------------------------------------------------
// Wind: an open surface has no leeward side.

TEST(ClothWind, PushesEitherSideAlike) {
  // Two horizontal sheets, one facing up and one facing down, in a wind blowing straight down:
  // both are pushed down, the same.
  const TriMesh up = makeCloth(1.0, 1.0, 4, 4);
  TriMesh down = transformed(up, [](const Vec3& p) { return p + Vec3{3.0, 0.0, 0.0}; });
  for (Triangle& t : down.triangles) std::swap(t[1], t[2]);
  Model model;
  model.gravity = {};
  addBody(model, cloth("up", up));
  addBody(model, cloth("down", down));
  Wind wind;
  wind.velocity = {0.0, -5.0, 0.0};
  wind.pressure = 1.0;
  model.wind = wind;
  World world(model, Integrator::SymplecticEuler, 1e-4);
  world.step();
  Vec3 momentum[2];
  for (uint32_t i = 0; i < model.vertexCount(); ++i) momentum[model.body[i]] += world.velocities()[i] * model.mass[i];
  // p = F dt with F = c A (w . n) n: 1 x 1 m^2 x 5 m/s, down.
  for (int b = 0; b < 2; ++b) {
    EXPECT_NEAR(momentum[b].y, -5.0 * 1e-4, 1e-12) << b;
    EXPECT_NEAR(momentum[b].x, 0.0, 1e-15) << b;
  }
}

// ------------------------------------------------------------------------------------------------
// Physics.

// A 1 m square cloth held flat by two corners of one side and let go: it falls, swings down about
// them and comes to rest hanging, stretching little (the cloth material stretches little and
// bends easily). Its swing about the corners is nearly a rigid motion, which the deformation
// damping leaves alone: air drag stops it, as it would a real towel.
TEST(ClothPhysics, HangingFromTwoCornersComesToRestStretchingLittle) {
  const int n = 12;
  const TriMesh mesh = transformed(makeCloth(1.0, 1.0, n, n), [](const Vec3& p) { return p + Vec3{0, 2, 0}; });
  BodyDesc desc = cloth("hanging", mesh);
  desc.pinned = {0, static_cast<uint32_t>(n)};  // (i, j) = (0, 0) and (n, 0): the corners at z = -0.5
  Model model;
  addBody(model, desc);
  model.drag = 2.0;
  const double dt = advisedStep(model, 4.0);
  World world(model, Integrator::RK4, dt);
  Monitor monitor(world);
  double mostKinetic = 0.0;
  const int perFrame = static_cast<int>(std::ceil(1.0 / 30.0 / dt));
  for (int frame = 0; frame < 120; ++frame) {  // 4 s
    for (int s = 0; s < perFrame; ++s) world.step();
    const std::optional<Failure> failure = monitor.check(world);
    ASSERT_FALSE(failure) << failure->message;
    mostKinetic = std::max(mostKinetic, kinetic(world));
  }
  EXPECT_GT(mostKinetic, 0.2);                    // it swung down (0.2 kg, its centre falling 0.5 m)
  EXPECT_LT(kinetic(world), 1e-3 * mostKinetic);  // and has stopped
  // The corners stayed; the cloth hangs below them.
  EXPECT_EQ(world.positions()[model.bodies[0].modelVertex[0]], mesh.positions[0]);
  EXPECT_LT(measureBody(world, 0).centroid.y, 2.0 - 0.4);
  // Strain: mean |l - l0| / l0 over the struts, and the largest.
  double sum = 0.0, most = 0.0;
  for (const Strut& s : model.struts) {
    const double strain =
        std::fabs(length(world.positions()[s.j] - world.positions()[s.i]) - s.restLength) / s.restLength;
    sum += strain;
    most = std::max(most, strain);
  }
  const double mean = sum / static_cast<double>(model.struts.size());
  EXPECT_LT(mean, 0.05);
  EXPECT_LT(most, 0.2);
  RecordProperty("mean_strain", std::to_string(mean));
  RecordProperty("max_strain", std::to_string(most));
}

// A cloth dropped flat (tilted a little) onto the ground lies on it at rest.
TEST(ClothPhysics, DroppedOntoAPlaneEndsAtRestOnIt) {
  const TriMesh mesh = transformed(makeCloth(1.0, 1.0, 12, 12), [](const Vec3& p) {
    return Vec3{p.x, 0.4 + 0.1 * p.x, p.z};  // 0.35 to 0.45 m up
  });
  Model model;
  addBody(model, cloth("dropped", mesh));
  model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, {}});
  const double dt = advisedStep(model, 2.5);
  model.colliders.restingSpeed = 4.0 * 9.81 * dt;  // as buildModel sets it
  World world(model, Integrator::RK4, dt);
  Monitor monitor(world);
  RestWatch rest;
  const int perFrame = static_cast<int>(std::ceil(1.0 / 30.0 / dt));
  for (int frame = 1; frame <= 75; ++frame) {  // 2.5 s
    for (int s = 0; s < perFrame; ++s) world.step();
    const std::optional<Failure> failure = monitor.check(world);
    ASSERT_FALSE(failure) << failure->message;
    if (frame > 45) rest.add(world.positions());
  }
  EXPECT_TRUE(rest.atRest(model.bodies[0]));
  double highest = 0.0;
  for (const Vec3& p : world.positions()) highest = std::max(highest, p.y);
  EXPECT_LT(highest, 0.01);  // flat on the ground (it started 0.35 m up)
  EXPECT_LT(measureBody(world, 0).penetration, 1e-6);
}

// A strip whose left half is pinned flat and whose right half starts turned up over it (135
// degrees about the middle): gravity folds the right half down onto the left. With self contact
// it lands on it and no triangle ever passes through another; without, it falls through.
TEST(ClothPhysics, FoldedOntoItselfNeverSelfIntersects) {
  const TriMesh flat = transformed(makeCloth(1.0, 0.3, 12, 4), [](const Vec3& p) { return p + Vec3{0, 1, 0}; });
  BodyDesc desc = cloth("strip", flat);
  for (uint32_t i = 0; i < flat.positions.size(); ++i) {
    if (flat.positions[i].x <= 1e-12) desc.pinned.push_back(i);  // the left half and the fold line
  }
  const double angle = 135.0 * kPi / 180.0;
  for (bool self : {true, false}) {
    desc.selfContact = self;
    Model model;
    addBody(model, desc);
    std::vector<Vec3> x = model.restPosition;
    for (Vec3& p : x) {
      if (p.x > 0.0) p = {p.x * std::cos(angle), 1.0 + p.x * std::sin(angle), p.z};
    }
    Model audit = model;
    audit.bodies[0].selfContact = true;  // the audit looks within the body either way
    const double dt = advisedStep(model, 1.2);
    World world(model, Integrator::RK4, dt);
    world.setState(x, std::vector<Vec3>(x.size()));
    ASSERT_TRUE(findIntersections(audit, world.positions(), 1).empty());
    const int perFrame = static_cast<int>(std::ceil(1.0 / 60.0 / dt));
    int crossed = -1;
    for (int frame = 1; frame <= 72 && crossed < 0; ++frame) {  // 1.2 s
      for (int s = 0; s < perFrame; ++s) world.step();
      if (!findIntersections(audit, world.positions(), 1).empty()) crossed = frame;
    }
    if (self) {
      EXPECT_EQ(crossed, -1) << "self contact let the strip through itself at frame " << crossed;
      // The right half lies on the left one: above it, and turned all the way over.
      double lowest = 2.0, rightmost = -1.0;
      for (uint32_t i = 0; i < x.size(); ++i) {
        if (model.restPosition[i].x <= 1e-12) continue;
        lowest = std::min(lowest, world.positions()[i].y);
        rightmost = std::max(rightmost, world.positions()[i].x);
      }
      EXPECT_GT(lowest, 1.0);
      EXPECT_LT(lowest, 1.02);
      EXPECT_LT(rightmost, 0.05);
      EXPECT_GT(world.bodyContacts()->sinceStart().impulses, 0u);
    } else {
      EXPECT_GT(crossed, 0) << "without self contact the strip should fall through itself";
    }
  }
}

// ------------------------------------------------------------------------------------------------
// Scene keys.

std::string dataMesh(const std::string& name) { return std::string(SPRINGY_SOURCE_DIR) + "/tests/data/meshes/" + name; }

std::string sceneError(const std::string& text, const std::string& path = "cloth.toml") {
  return errorOf([&] { parseScene(text, path); });
}

TEST(ClothScene, ShapeKeysAndPins) {
  const SceneDesc scene = parseScene(
      "[[body]]\nshape = \"cloth\"\nsize = [2.0, 1.0]\nresolution = [8, 4]\nposition = [0, 1, 0]\n"
      "pin_side = \"left\"\n",
      "cloth.toml");
  const BodyDesc& b = scene.bodies[0];
  EXPECT_TRUE(b.cloth);
  EXPECT_EQ(b.mesh.positions.size(), 45u);
  EXPECT_EQ(b.mesh.triangles.size(), 64u);
  const Bounds box = boundsOf(b.mesh.positions);
  EXPECT_DOUBLE_EQ(box.size().x, 2.0);
  EXPECT_DOUBLE_EQ(box.size().z, 1.0);
  EXPECT_EQ(box.lo.y, 1.0);
  // pin_side: the whole left side (x = -1), 5 vertices; pin = ["left"] would pin one.
  ASSERT_EQ(b.pinned.size(), 5u);
  for (uint32_t i : b.pinned) EXPECT_EQ(b.mesh.positions[i].x, -1.0);
  const SceneDesc one = parseScene("[[body]]\nshape = \"cloth\"\nresolution = 4\npin = [\"left\"]\n", "cloth.toml");
  EXPECT_EQ(one.bodies[0].pinned.size(), 1u);
  // Defaults: 1 m square, 20 x 20 quads; a number for both sides.
  const SceneDesc plain = parseScene("[[body]]\nshape = \"cloth\"\nsize = 0.5\n", "cloth.toml");
  EXPECT_EQ(plain.bodies[0].mesh.positions.size(), 441u);
  EXPECT_DOUBLE_EQ(boundsOf(plain.bodies[0].mesh.positions).size().z, 0.5);
  // Several sides, named twice: each vertex of the two sides, a corner twice (harmless).
  const SceneDesc sides = parseScene(
      "[[body]]\nshape = \"cloth\"\nresolution = 4\npin_side = [\"left\", \"back\", \"left\"]\n", "cloth.toml");
  EXPECT_EQ(sides.bodies[0].pinned.size(), 10u);
  // pin = ["all"]: a static body.
  const SceneDesc all =
      parseScene("[[body]]\nshape = \"icosphere\"\nsubdivisions = 1\npin = [\"all\", \"top\"]\n", "s.toml");
  EXPECT_EQ(all.bodies[0].pinned.size(), 43u);
  EXPECT_EQ(buildModel(all).pinned.size(), 42u);
  // The model: an open body, no hinge on the border, the cloth material.
  const Model model = buildModel(scene);
  EXPECT_TRUE(model.bodies[0].open);
  EXPECT_EQ(model.bodies[0].restVolume, 0.0);
  EXPECT_EQ(model.struts.size(), 8u * 5u + 4u * 9u + 32u);  // rows, columns, diagonals
  EXPECT_EQ(model.hinges.size(), model.struts.size() - 2u * (8u + 4u));
  EXPECT_EQ(model.pinned.size(), 5u);
}

TEST(ClothScene, ErrorsNameFileLineAndKey) {
  const std::string body = "[[body]]\nshape = \"cloth\"\n";
  struct Case {
    std::string text, line, pieces[2];
  };
  const Case cases[] = {
      {body + "resolution = 0\n", "cloth.toml:3:", {"'resolution'", "between 1 and 512, got 0"}},
      {body + "resolution = [4, 600]\n", "cloth.toml:3:", {"'resolution'", "between 1 and 512, got 600"}},
      {body + "resolution = [4, 4, 4]\n", "cloth.toml:3:", {"'resolution'", "two integers"}},
      {body + "resolution = [4.5, 4]\n", "cloth.toml:3:", {"'resolution'", "integer"}},
      {body + "size = [1, -2]\n", "cloth.toml:3:", {"'size'", "positive"}},
      {body + "size = \"big\"\n", "cloth.toml:3:", {"'size'", "two numbers"}},
      {body + "cloth = false\n", "cloth.toml:3:", {"'cloth'", "always cloth = true"}},
      {body + "cloth = 1\n", "cloth.toml:3:", {"'cloth'", "true or false"}},
      {body + "radius = 2\n", "cloth.toml:3:", {"unknown key 'radius'", ""}},
      {body + "pin_side = \"middle\"\n", "cloth.toml:3:", {"'pin_side'", "unknown side 'middle'"}},
      {body + "pin_side = [1]\n", "cloth.toml:3:", {"'pin_side'", "entries must be sides"}},
      {"[[body]]\nshape = \"mesh\"\nmesh = \"x.obj\"\ncloth = true\nproxy = \"auto\"\n",
       "cloth.toml:5:",
       {"'proxy'", "never through a proxy"}},
      {"[[body]]\nshape = \"mesh\"\nmesh = \"x.obj\"\ncloth = true\nproxy_vertices = 300\n",
       "cloth.toml:5:",
       {"'proxy_vertices'", "never through a proxy"}},
  };
  for (const Case& c : cases) {
    const std::string message = sceneError(c.text);
    EXPECT_EQ(message.rfind(c.line, 0), 0u) << c.text << "\n-> " << message;
    for (const std::string& piece : c.pieces)
      EXPECT_NE(message.find(piece), std::string::npos) << c.text << "\n-> " << message;
  }
}

TEST(ClothScene, MeshFileAsClothIsValidatedAndKeptAsItIs) {
  // An open box (a cube without its top): with cloth = true it is simulated as it is, open; by
  // default the open mesh would be wrapped in a closed proxy.
  const std::string box = "[[body]]\nshape = \"mesh\"\nmesh = \"" + dataMesh("cube_hole.obj") + "\"\ncloth = true\n";
  const SceneDesc scene = parseScene(box, "cloth.toml");
  EXPECT_TRUE(scene.bodies[0].cloth);
  EXPECT_TRUE(scene.bodies[0].note.empty());  // no proxy
  EXPECT_TRUE(scene.bodies[0].drawMesh.positions.empty());
  EXPECT_EQ(findManifoldProblem(scene.bodies[0].mesh), "edge (4, 5) belongs to 1 triangle: the mesh has a hole");
  const Model model = buildModel(scene);
  EXPECT_TRUE(model.bodies[0].open);
  EXPECT_EQ(model.bodies[0].restVolume, 0.0);
  // A mesh with a non-manifold edge (a fin on a sheet) is refused naming the file, the line, the
  // key and the edge.
  const std::string path = dataMesh("sheet_fin.obj");
  const std::string message = sceneError("[[body]]\nshape = \"mesh\"\ncloth = true\nmesh = \"" + path + "\"\n");
  EXPECT_EQ(message.rfind("cloth.toml:4:", 0), 0u) << message;
  EXPECT_NE(message.find("'mesh'"), std::string::npos) << message;
  EXPECT_NE(message.find(path + ": edge ("), std::string::npos) << message;
  EXPECT_NE(message.find("is shared by 3 triangles: non-manifold edge"), std::string::npos) << message;
  // The edge named is the one the squares share, (1, 0, 0)-(1, 0, 1), in the welded mesh's numbers.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m, std::regex(R"(edge \((\d+), (\d+)\))"))) << message;
  const TriMesh welded = readWeldedMesh(path);
  const Vec3 a = welded.positions.at(std::stoul(m[1])), b = welded.positions.at(std::stoul(m[2]));
  EXPECT_EQ(a.x, 1.0);
  EXPECT_EQ(b.x, 1.0);
  EXPECT_EQ(a.y + b.y, 0.0);
  EXPECT_EQ(a.z + b.z, 1.0);
  // simplify is for closed meshes.
  const std::string simplify = sceneError(box + "simplify = 10\n");
  EXPECT_EQ(simplify.rfind("cloth.toml:5:", 0), 0u) << simplify;
  EXPECT_NE(simplify.find("'simplify'"), std::string::npos) << simplify;
}

}  // namespace
}  // namespace springy

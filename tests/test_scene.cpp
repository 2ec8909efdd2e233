// Scene files: a valid scene builds the model it describes; every error names the file, the
// line and the key; pins, transforms and colliders do what the format says.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "sim/error.h"
#include "sim/mesh.h"
#include "sim/world.h"

namespace springy {
namespace {

const std::string kPath = "/virtual/dir/test.toml";  // parseScene only uses it in messages and paths

std::string dataPath(const std::string& name) { return std::string(SPRINGY_SOURCE_DIR) + "/tests/data/scenes/" + name; }

// The error message parseScene throws for `text` ("" if it does not throw).
std::string errorOf(const std::string& text, const std::string& path = kPath) {
  try {
    parseScene(text, path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Checks that the message starts with "PATH:LINE:" and contains every piece.
void expectError(const std::string& text, int line, const std::vector<std::string>& pieces) {
  const std::string message = errorOf(text);
  ASSERT_FALSE(message.empty()) << "no error for:\n" << text;
  const std::string prefix = kPath + ":" + std::to_string(line) + ":";
  EXPECT_EQ(message.rfind(prefix, 0), 0u) << "expected prefix '" << prefix << "' in: " << message;
  for (const std::string& piece : pieces) {
    EXPECT_NE(message.find(piece), std::string::npos) << "'" << piece << "' missing from: " << message;
  }
}

const std::string kBody = R"([[body]]
shape = "octahedron_sphere"
radius = 6
subdivisions = 6
position = [0, 20, 0]
mass = 8
)";

Vec3 centroidOf(const std::vector<Vec3>& points) {
  Vec3 c;
  for (const Vec3& p : points) c += p;
  return c / static_cast<double>(points.size());
}

void expectNear(const Vec3& a, const Vec3& b, double tolerance, const std::string& what = "") {
  EXPECT_LT(length(a - b), tolerance) << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", "
                                      << b.y << ", " << b.z << ")";
}

// ---------------------------------------------------------------------------------------------
// Valid scenes.

TEST(Scene, MinimalSceneParsesWithDefaults) {
  const SceneDesc scene = parseScene(kBody, kPath);
  EXPECT_EQ(scene.name, "test");  // the file's stem
  EXPECT_EQ(scene.path, kPath);
  // Defaults of sim/scene.h.
  EXPECT_EQ(scene.dt, 0.002);
  EXPECT_EQ(scene.duration, 10.0);
  EXPECT_EQ(scene.substeps, 1);
  EXPECT_EQ(scene.integrator, Integrator::RK4);
  EXPECT_EQ(scene.gravity, (Vec3{0, -9.81, 0}));
  EXPECT_EQ(scene.drag, 0.0);
  EXPECT_FALSE(scene.wind.has_value());
  EXPECT_TRUE(scene.planes.empty());
  EXPECT_TRUE(scene.triangleColliders.empty());
  EXPECT_EQ(scene.view.render.width, 1280);
  EXPECT_EQ(scene.view.render.height, 720);

  ASSERT_EQ(scene.bodies.size(), 1u);
  const BodyDesc& body = scene.bodies[0];
  EXPECT_EQ(body.name, "body 1");
  EXPECT_EQ(body.mass, 8.0);
  ASSERT_EQ(body.mesh.positions.size(), 146u);  // 4 n^2 + 2
  EXPECT_EQ(body.mesh.triangles.size(), 288u);  // 8 n^2
  expectNear(centroidOf(body.mesh.positions), {0, 20, 0}, 1e-12, "centroid");
  EXPECT_EQ(body.mesh.positions[0], (Vec3{0, 26, 0}));  // the top pole
  for (const Vec3& p : body.mesh.positions) EXPECT_NEAR(length(p - Vec3{0, 20, 0}), 6.0, 1e-12);
  EXPECT_TRUE(body.pinned.empty());

  const Model model = buildModel(scene);
  ASSERT_EQ(model.mass.size(), 146u);
  double total = 0.0;
  for (double m : model.mass) total += m;
  EXPECT_NEAR(total, 8.0, 1e-12);
  // A closed mesh: every edge is shared by two triangles, so edges = 3 F / 2, one strut and
  // one hinge per edge.
  EXPECT_EQ(model.struts.size(), 432u);
  EXPECT_EQ(model.hinges.size(), 432u);
  EXPECT_EQ(model.faces.size(), 288u);
  EXPECT_EQ(model.gravity, (Vec3{0, -9.81, 0}));
  EXPECT_TRUE(model.pinned.empty());
  EXPECT_TRUE(std::all_of(model.invMass.begin(), model.invMass.end(), [](double w) { return w > 0.0; }));
  // No collider, so no collide stage.
  EXPECT_TRUE(model.colliders.empty());
  const World world(model, scene.integrator, stepSize(scene));
  EXPECT_FALSE(world.collides());
  EXPECT_EQ(world.dt(), 0.002);
}

TEST(Scene, AllSectionsAreRead) {
  const std::string text = R"(# every section once
[scene]
name = "everything"
duration = 3.5
dt = 0.004
substeps = 4
integrator = "leapfrog"
resting_speed = 0.25

[environment]
gravity = [0, -1.62, 0]
drag = 0.5
[environment.wind]
velocity = [3, 0, 1]
gust_strength = 0.2
gust_period = 4
pressure = 1.5
seed = 9

)" + kBody + R"(velocity = [1, 2, 3]
color = [0.1, 0.2, 0.3]

[[prop]]
shape = "box"
center = [1, 2, 3]
size = [4, 5, 6]

[render]
width = 640
height = 360
fps = 25
[render.camera]
position = [0, 10, 30]
target = [0, 5, 0]
fov = 45
[render.light]
ambient = 0.2
)";
  const SceneDesc scene = parseScene(text, kPath);
  EXPECT_EQ(scene.name, "everything");
  EXPECT_EQ(scene.duration, 3.5);
  EXPECT_EQ(scene.dt, 0.004);
  EXPECT_EQ(scene.substeps, 4);
  EXPECT_EQ(stepSize(scene), 0.001);
  EXPECT_EQ(scene.integrator, Integrator::Leapfrog);
  EXPECT_EQ(scene.restingSpeed, 0.25);
  EXPECT_EQ(scene.gravity, (Vec3{0, -1.62, 0}));
  EXPECT_EQ(scene.drag, 0.5);
  ASSERT_TRUE(scene.wind.has_value());
  EXPECT_EQ(scene.wind->velocity, (Vec3{3, 0, 1}));
  EXPECT_EQ(scene.wind->gustStrength, 0.2);
  EXPECT_EQ(scene.wind->gustPeriod, 4.0);
  EXPECT_EQ(scene.wind->pressure, 1.5);
  EXPECT_EQ(scene.wind->seed, 9u);
  EXPECT_EQ(scene.bodies[0].velocity, (Vec3{1, 2, 3}));
  EXPECT_EQ(scene.view.bodies[0].color, (Vec3{0.1, 0.2, 0.3}));
  ASSERT_EQ(scene.view.props.size(), 1u);
  EXPECT_EQ(scene.view.props[0].shape, PropDesc::Shape::Box);
  EXPECT_EQ(scene.view.props[0].size, (Vec3{4, 5, 6}));
  EXPECT_EQ(scene.view.render.width, 640);
  EXPECT_EQ(scene.view.render.fps, 25.0);
  EXPECT_EQ(scene.view.render.camera.target, (Vec3{0, 5, 0}));
  EXPECT_EQ(scene.view.render.camera.fov, 45.0);
  EXPECT_EQ(scene.view.render.light.ambient, 0.2);

  const Model model = buildModel(scene);
  EXPECT_EQ(model.gravity, (Vec3{0, -1.62, 0}));
  EXPECT_EQ(model.drag, 0.5);
  ASSERT_TRUE(model.wind.has_value());
  EXPECT_EQ(model.colliders.restingSpeed, 0.25);  // explicit, not automatic
  for (const Vec3& v : model.initialVelocity) EXPECT_EQ(v, (Vec3{1, 2, 3}));
  // Gust phases come from the seed: the same scene gives the same wind.
  const Model again = buildModel(scene);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(model.wind->phase[i], again.wind->phase[i]);
}

TEST(Scene, LoadsFilesAndResolvesMeshPathsRelativeToTheScene) {
  const SceneDesc scene = loadScene(dataPath("minimal.toml"));
  EXPECT_EQ(scene.name, "minimal test");
  EXPECT_EQ(scene.integrator, Integrator::VelocityVerlet);
  EXPECT_EQ(stepSize(scene), 0.0005);
  ASSERT_EQ(scene.bodies.size(), 1u);
  EXPECT_EQ(scene.bodies[0].mesh.positions.size(), 42u);  // icosphere level 1
  ASSERT_EQ(scene.planes.size(), 1u);
  EXPECT_EQ(scene.planes[0].material.restitution, 0.4);
  EXPECT_EQ(scene.planes[0].material.friction, 0.6);
  const Model model = buildModel(scene);
  EXPECT_NEAR(model.colliders.restingSpeed, 4 * 9.81 * 0.0005, 1e-15);  // automatic: 4 |g| dt

  const SceneDesc meshes = loadScene(dataPath("mesh_body.toml"));
  EXPECT_EQ(meshes.name, "mesh_body");
  ASSERT_EQ(meshes.bodies.size(), 1u);
  EXPECT_EQ(meshes.bodies[0].mesh.positions.size(), 8u);  // the STL cube, welded
  EXPECT_NEAR(signedVolume(meshes.bodies[0].mesh.positions, meshes.bodies[0].mesh.triangles), 8.0, 1e-12);
  ASSERT_EQ(meshes.triangleColliders.size(), 1u);
  const TriangleCollider& box = meshes.triangleColliders[0];
  EXPECT_EQ(box.name, "box");
  EXPECT_EQ(box.mesh.triangles.size(), 12u);
  // Moved by its position.
  EXPECT_NEAR(boundsOf(box.mesh.positions).center().y - boundsOf(meshes.bodies[0].mesh.positions).center().y, -10.0,
              1e-12);

  try {
    loadScene(dataPath("no_such_scene.toml"));
    ADD_FAILURE() << "no error for a missing scene file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_scene.toml"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Errors: every one names the file and line.

TEST(Scene, TheMaterialIsTheBodysUnlessAnElementKeyIsGiven) {
  // No stiffness keys: the body material with its defaults scaled by the body's size (the
  // octahedron sphere's area is about that of a sphere of radius 6, so L is about 6 m).
  const SceneDesc plain = parseScene(kBody, kPath);
  EXPECT_EQ(plain.bodies[0].material, MaterialModel::Body);
  EXPECT_FALSE(plain.stepGiven);
  const Model model = buildModel(plain);
  const BodyInfo& info = model.bodies[0];
  double area = 0.0;
  for (const Triangle& t : model.faces) {
    area += 0.5 * length(cross(model.restPosition[t[1]] - model.restPosition[t[0]],
                               model.restPosition[t[2]] - model.restPosition[t[0]]));
  }
  const double density = 8.0 / area, L = std::sqrt(area / (4 * kPi));
  const double omega = 2 * kPi / (kDefaultStretchPeriod * L), omegaBend = 2 * kPi / (kDefaultBendPeriod * L);
  EXPECT_NEAR(info.membraneModulus, density * L * L * omega * omega, 1e-12 * info.membraneModulus);
  EXPECT_NEAR(info.bendingModulus, density * std::pow(L, 4) * omegaBend * omegaBend, 1e-12 * info.bendingModulus);
  EXPECT_NEAR(info.deformationDamping, 2.0 / kDefaultDeformationDecay, 1e-12);
  // No strut or hinge damps on its own: the body's deformation damping does.
  for (const Strut& st : model.struts) EXPECT_EQ(st.damping, 0.0);
  for (const Hinge& h : model.hinges) EXPECT_EQ(h.damping, 0.0);
  // Any element key selects the seed's element material, as in the showcase scenes.
  const SceneDesc element = parseScene(kBody + "hinge_decay = 3\n[scene]\ndt = 0.001\n", kPath);
  EXPECT_EQ(element.bodies[0].material, MaterialModel::Element);
  EXPECT_EQ(buildModel(element).bodies[0].deformationDamping, 0.0);
  EXPECT_TRUE(element.stepGiven);
  // Its own keys.
  const SceneDesc own = parseScene(kBody + "stretch_period = 0.2\nbend_period = 0\ndeformation_decay = 0\n", kPath);
  const Model ownModel = buildModel(own);
  EXPECT_EQ(ownModel.hinges.size(), 0u);
  EXPECT_EQ(ownModel.bodies[0].deformationDamping, 0.0);
  EXPECT_NEAR(ownModel.bodies[0].membraneModulus, density * L * L * std::pow(2 * kPi / 0.2, 2),
              1e-12 * ownModel.bodies[0].membraneModulus);
}

TEST(SceneErrors, MaterialKeysOfTheOtherKindAreErrors) {
  expectError(kBody + "material = \"body\"\nstrut_period = 0.1\n", 8,
              {"'strut_period'", "element key", "stretch_period"});
  expectError(kBody + "strut_period = 0.1\nbend_period = 0.5\n", 8, {"'bend_period'", "body material key"});
  expectError(kBody + "material = \"body\"\nmodel = \"all_pairs\"\n", 7, {"'material'", "all_pairs"});
  expectError(kBody + "material = \"stiff\"\n", 7, {"'material'", "body, element"});
  expectError(kBody + "deformation_decay = -1\n", 7, {"'deformation_decay'", "[1e-06, 1e+06]"});
}

TEST(SceneErrors, UnknownKeysAreErrorsWithTheirLine) {
  // In [[body]]: line 7.
  expectError(kBody + "masss = 8\n", 7, {"'masss'", "[[body]] #1"});
  // In the second body: its own number.
  expectError(kBody + kBody + "colour = [1, 0, 0]\n", 13, {"'colour'", "[[body]] #2"});
  // In [scene].
  expectError("[scene]\ndt = 0.01\ntimestep = 0.01\n" + kBody, 3, {"'timestep'", "[scene]"});
  // In [render.camera].
  expectError(kBody + "[render]\nwidth = 640\n[render.camera]\nfov = 50\nzoom = 2\n", 11, {"'zoom'", "[render.camera]"});
  // In [environment.wind].
  expectError("[environment]\n[environment.wind]\nspeed = 3\n" + kBody, 3, {"'speed'", "[environment.wind]"});
  // A key of another shape is unknown for this one (radius belongs to spheres).
  expectError("[[body]]\nshape = \"cube\"\nradius = 2\n", 3, {"'radius'"});
  // An unknown top-level table.
  expectError(kBody + "\n[physics]\nstiff = true\n", 8, {"'physics'"});
  // An unknown top-level key.
  expectError("gravity = [0, -9.81, 0]\n" + kBody, 1, {"'gravity'"});
}

TEST(SceneErrors, WrongTypesNameTheKeyAndTheExpectedType) {
  expectError("[[body]]\nmass = \"heavy\"\n", 2, {"'mass'", "number"});
  expectError("[scene]\ndt = true\n" + kBody, 2, {"'dt'", "number"});
  expectError("[scene]\nsubsteps = 2.5\n" + kBody, 2, {"'substeps'", "integer"});
  expectError(kBody + "velocity = [1, 2]\n", 7, {"'velocity'", "three numbers"});
  expectError("[scene]\nintegrator = \"midpoint\"\n" + kBody, 2, {"'integrator'", "rk4", "symplectic_euler"});
  expectError(kBody + "[render]\nshadows = \"yes\"\n", 8, {"'shadows'", "true or false"});
  expectError(kBody + "[[plane]]\nnormal = [0, 0, 0]\n", 8, {"'normal'", "zero"});
  expectError("[scene]\n" + kBody + "[[scene]]\n", 8, {"scene"});  // must be a table, once
  expectError("plane = 3\n" + kBody, 1, {"'plane'", "[[plane]]"});  // not an array of tables
}

TEST(SceneErrors, MissingMeshFileNamesTheSceneLineKeyAndPath) {
  const std::string path = dataPath("missing_mesh.toml");
  try {
    loadScene(path);
    FAIL() << "no error for a missing mesh file";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path + ":5:", 0), 0u) << message;
    EXPECT_NE(message.find("'mesh'"), std::string::npos) << message;
    EXPECT_NE(message.find(dataPath("nope.obj")), std::string::npos) << message;  // resolved next to the scene
  }
  // The same in memory, with a relative scene path.
  const std::string message = errorOf("[[body]]\nshape = \"mesh\"\nmesh = \"nope.obj\"\n", "scenes/here.toml");
  EXPECT_EQ(message.rfind("scenes/here.toml:3:", 0), 0u) << message;
  EXPECT_NE(message.find("scenes/nope.obj"), std::string::npos) << message;
  // shape = "mesh" without a mesh key.
  expectError("[[body]]\nshape = \"mesh\"\n", 1, {"mesh = \"FILE\""});
}

TEST(SceneErrors, OutOfRangeValues) {
  expectError(kBody + "[[plane]]\nrestitution = 1.5\n", 8, {"'restitution'", "[0, 1]", "1.5"});
  expectError(kBody + "[[plane]]\nfriction = -0.1\n", 8, {"'friction'"});
  expectError(kBody + "[[plane]]\ndamping = 20\n", 7, {"[[plane]]", "damping_layer"});
  expectError(kBody + "[[plane]]\ndamping = -1\ndamping_layer = 0.5\n", 8, {"'damping'"});
  expectError("[[body]]\nradius = -2\n", 2, {"'radius'", "positive", "-2"});
  // Masses and times have ranges that keep the derived constants finite (sim/limits.h).
  expectError("[[body]]\nmass = 0\n", 2, {"'mass'", "must be in [1e-09, 1e+09], got 0"});
  expectError("[[body]]\nvolume_period = -0.1\n", 2, {"'volume_period'", "[1e-06, 1e+06]", "-0.1"});
  expectError("[[body]]\nsubdivisions = 0\n", 2, {"'subdivisions'", "between 1 and 256", "0"});
  expectError("[scene]\ndt = -0.001\n" + kBody, 2, {"'dt'", "positive"});
  expectError("[[body]]\nscale = [1, 0, 1]\n", 2, {"'scale'", "positive"});
  expectError(kBody + "color = [1.2, 0, 0]\n", 7, {"'color'", "[0, 1]"});
  // An odd width: the error points at the [render] table.
  expectError(kBody + "\n[render]\nwidth = 1281\n", 8, {"[render]", "even"});
  expectError(kBody + "[render]\nwidth = 8\n", 8, {"'width'", "between 16 and 7680"});
  expectError(kBody + "[render]\n[render.camera]\ntarget = [0, 0, 0]\nangles = [10, 0, 0]\n", 8,
              {"[render.camera]", "either target or angles"});
}

TEST(SceneErrors, TomlSyntaxErrorsHaveFileAndLine) {
  expectError("[[body]]\nshape = \"octahedron_sphere\"\nmass = = 8\n", 3, {});
  expectError("[[body]]\nmass = 8\nname = \"unterminated\n", 3, {});
  expectError("[scene]\ndt = 0.01\n[scene]\n" + kBody, 3, {});  // a table defined twice
}

TEST(SceneErrors, SceneWithoutBodies) {
  const std::string message = errorOf("[scene]\ndt = 0.01\n");
  EXPECT_EQ(message.rfind(kPath, 0), 0u) << message;
  EXPECT_NE(message.find("no [[body]]"), std::string::npos) << message;
}

// ---------------------------------------------------------------------------------------------
// Pins.

TEST(Scene, PinRules) {
  const SceneDesc top = parseScene(kBody + "pin = [\"top\"]\n", kPath);
  EXPECT_EQ(top.bodies[0].pinned, (std::vector<uint32_t>{0}));  // the pole, vertex 0
  const Model model = buildModel(top);
  const std::vector<uint32_t>& modelVertex = model.bodies[0].modelVertex;  // mesh -> model index
  EXPECT_EQ(model.pinned, (std::vector<uint32_t>{modelVertex[0]}));
  EXPECT_EQ(model.invMass[modelVertex[0]], 0.0);
  EXPECT_GT(model.invMass[modelVertex[1]], 0.0);

  // Every rule picks the extreme vertex along its axis.
  const std::vector<Vec3>& p = top.bodies[0].mesh.positions;
  const std::pair<const char*, std::function<double(const Vec3&)>> rules[] = {
      {"top", [](const Vec3& v) { return v.y; }},    {"bottom", [](const Vec3& v) { return -v.y; }},
      {"right", [](const Vec3& v) { return v.x; }},  {"left", [](const Vec3& v) { return -v.x; }},
      {"back", [](const Vec3& v) { return v.z; }},   {"front", [](const Vec3& v) { return -v.z; }},
  };
  for (const auto& [rule, key] : rules) {
    const SceneDesc scene = parseScene(kBody + "pin = [\"" + rule + "\"]\n", kPath);
    ASSERT_EQ(scene.bodies[0].pinned.size(), 1u);
    const uint32_t i = scene.bodies[0].pinned[0];
    for (const Vec3& q : p) EXPECT_GE(key(p[i]), key(q)) << rule;
  }
  // Indices and rules mix; pins are body-local indices, global ones after the first body.
  // (The second body is a ghost: it sits where the first is.)
  const SceneDesc two = parseScene(kBody + kBody + "contact = false\npin = [5, \"top\"]\n", kPath);
  EXPECT_EQ(two.bodies[1].pinned, (std::vector<uint32_t>{5, 0}));
  const Model twoModel = buildModel(two);
  std::vector<uint32_t> expected{twoModel.bodies[1].modelVertex[5], twoModel.bodies[1].modelVertex[0]};
  std::sort(expected.begin(), expected.end());
  EXPECT_GE(expected[0], 146u);  // global indices: after the first body's 146
  EXPECT_EQ(twoModel.pinned, expected);

  // pin_near: the nearest vertex to each point, in world coordinates.
  const Vec3 target{5.1, 21.3, -0.8};
  const SceneDesc near = parseScene(kBody + "pin_near = [[5.1, 21.3, -0.8], [0, 0, 0]]\n", kPath);
  ASSERT_EQ(near.bodies[0].pinned.size(), 2u);
  const uint32_t chosen = near.bodies[0].pinned[0];
  for (const Vec3& q : p) EXPECT_LE(length(p[chosen] - target), length(q - target));
  EXPECT_GT(chosen, 0u);
  expectNear(p[near.bodies[0].pinned[1]], {0, 14, 0}, 1e-12, "nearest to the origin: the bottom pole");

  // Errors name the vertex.
  expectError(kBody + "pin = [146]\n", 7, {"'pin'", "vertex 146 does not exist", "146 vertices"});
  expectError(kBody + "pin = [-1]\n", 7, {"'pin'", "vertex -1"});
  expectError(kBody + "pin = [\"middle\"]\n", 7, {"'pin'", "'middle'"});
  expectError(kBody + "pin_near = [[1, 2]]\n", 7, {"'pin_near'"});
}

// ---------------------------------------------------------------------------------------------
// Transforms: scale, then rotate (Euler angles in degrees, z then x then y), then translate.

std::vector<Vec3> octahedron(const std::string& transform) {
  // subdivisions = 1: the six corners of an octahedron of radius 1 on the axes.
  const SceneDesc scene = parseScene("[[body]]\nshape = \"octahedron_sphere\"\nsubdivisions = 1\n" + transform, kPath);
  return scene.bodies[0].mesh.positions;
}

TEST(Scene, TransformRotatesScalesAndMoves) {
  const std::vector<Vec3> rest = octahedron("");
  ASSERT_EQ(rest.size(), 6u);
  auto check = [&](const std::string& transform, const std::function<Vec3(const Vec3&)>& expected) {
    const std::vector<Vec3> moved = octahedron(transform);
    ASSERT_EQ(moved.size(), rest.size());
    for (std::size_t i = 0; i < rest.size(); ++i) expectNear(moved[i], expected(rest[i]), 1e-12, transform);
  };
  // 90 degrees about y takes +x to -z (and +z to +x).
  check("rotation = [0, 90, 0]\n", [](const Vec3& p) { return Vec3{p.z, p.y, -p.x}; });
  // About z: +x to +y. About x: +y to +z.
  check("rotation = [0, 0, 90]\n", [](const Vec3& p) { return Vec3{-p.y, p.x, p.z}; });
  check("rotation = [90, 0, 0]\n", [](const Vec3& p) { return Vec3{p.x, -p.z, p.y}; });
  // The order is z, then x, then y: [90, 0, 90] takes +x to +z (x-then-z would give +y).
  check("rotation = [90, 0, 90]\n", [](const Vec3& p) { return Vec3{-p.y, -p.z, p.x}; });
  // [90, 90, 0]: x, then y.
  check("rotation = [90, 90, 0]\n", [](const Vec3& p) { return Vec3{p.y, -p.z, -p.x}; });
  // Scale doubles every distance from the centre; a vector scale acts before the rotation.
  check("scale = 2\n", [](const Vec3& p) { return p * 2.0; });
  check("scale = [2, 1, 1]\nrotation = [0, 90, 0]\n", [](const Vec3& p) { return Vec3{p.z, p.y, -2 * p.x}; });
  // Position moves last.
  check("scale = 3\nrotation = [0, 90, 0]\nposition = [1, 2, 3]\n",
        [](const Vec3& p) { return Vec3{3 * p.z + 1, 3 * p.y + 2, -3 * p.x + 3}; });

  // scale = 2 on the radius-6 sphere: radius 12 about its position.
  const SceneDesc big = parseScene(kBody + "scale = 2\n", kPath);
  for (const Vec3& p : big.bodies[0].mesh.positions) EXPECT_NEAR(length(p - Vec3{0, 20, 0}), 12.0, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Colliders.

TEST(Scene, PlaneAndTrianglesBuildBothColliders) {
  const std::string text = kBody + R"(
[[plane]]
point = [0, -1, 0]
normal = [0, 2, 0]
restitution = 0.2
friction = 0.9

[[triangles]]
name = "ramp"
quads = [[[-10, 5, -10], [10, 5, -10], [10, 5, 10], [-10, 5, 10]],
         [[-10, 0, 20], [10, 0, 20], [10, 5, 10], [-10, 5, 10]]]
position = [0, 1, 0]
restitution = 0.1
friction = 0.5
)";
  const SceneDesc scene = parseScene(text, kPath);
  ASSERT_EQ(scene.planes.size(), 1u);
  EXPECT_EQ(scene.planes[0].normal, (Vec3{0, 1, 0}));  // normalised
  ASSERT_EQ(scene.triangleColliders.size(), 1u);
  const TriangleCollider& ramp = scene.triangleColliders[0];
  EXPECT_EQ(ramp.name, "ramp");
  EXPECT_EQ(ramp.mesh.positions.size(), 8u);
  ASSERT_EQ(ramp.mesh.triangles.size(), 4u);  // two per quad
  EXPECT_EQ(ramp.mesh.triangles[2], (Triangle{4, 5, 6}));
  EXPECT_EQ(ramp.mesh.triangles[3], (Triangle{4, 6, 7}));
  EXPECT_EQ(ramp.mesh.positions[0], (Vec3{-10, 6, -10}));  // moved by position
  EXPECT_EQ(ramp.material.restitution, 0.1);
  EXPECT_EQ(ramp.material.friction, 0.5);

  const Model model = buildModel(scene);
  ASSERT_EQ(model.colliders.planes.size(), 1u);
  ASSERT_EQ(model.colliders.meshes.size(), 1u);
  EXPECT_EQ(model.colliders.planes[0].material.restitution, 0.2);
  EXPECT_EQ(model.colliders.planes[0].material.friction, 0.9);
  EXPECT_NEAR(model.colliders.restingSpeed, 4 * 9.81 * 0.002, 1e-15);
  const World world(model, scene.integrator, stepSize(scene));
  EXPECT_TRUE(world.collides());
  EXPECT_FALSE(model.colliders.meshes[0].nodes.empty());  // setup built the BVH

  // The ramp is a collider: a path down through its top quad stops on it (y = 6), above the
  // plane (y = -1).
  ContactHit hit;
  ASSERT_TRUE(world.model().colliders.firstHit({1, 20, 2}, {1, -20, 2}, hit));
  EXPECT_NEAR(hit.point.y, 6.0, 1e-12);
  EXPECT_EQ(hit.material.restitution, 0.1);

  // Explicit triangles: vertices + indices; a bad index is an error on its line.
  const SceneDesc tri = parseScene(kBody + "[[triangles]]\nvertices = [[0, 0, 0], [1, 0, 0], [0, 0, 1]]\n"
                                           "indices = [[0, 2, 1]]\n",
                                   kPath);
  EXPECT_EQ(tri.triangleColliders[0].mesh.triangles[0], (Triangle{0, 2, 1}));
  expectError(kBody + "[[triangles]]\nvertices = [[0, 0, 0], [1, 0, 0], [0, 0, 1]]\nindices = [[0, 2, 3]]\n", 9,
              {"'indices'"});
  expectError(kBody + "[[triangles]]\nquads = [[[0, 0, 0], [1, 0, 0], [0, 0, 1]]]\n", 8, {"'quads'", "four corners"});
  expectError(kBody + "[[triangles]]\nname = \"empty\"\n", 7, {"needs triangles"});
}

}  // namespace
}  // namespace springy

// The body material (MaterialModel::Body, sim/model.h): moduli scaled by each element's rest
// geometry, and deformation damping relative to the body's rigid motion. Its laws (rigid
// motion feels nothing, momentum and angular momentum are kept, energy only leaves, every
// deformation decays at the stated rate) and its promise: a sphere behaves the same at every
// mesh resolution.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/model.h"
#include "sim/shapes.h"
#include "sim/stability.h"
#include "sim/world.h"

namespace springy {
namespace {

Model sphereModel(const TriMesh& mesh, double decay, double mass = 1.5) {
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = mesh;
  desc.mass = mass;
  desc.material = MaterialModel::Body;
  desc.deformationDecay = decay;
  Model model;
  model.gravity = {};
  addBody(model, desc);
  return model;
}

Vec3 momentumOf(const Model& m, const std::vector<Vec3>& v) {
  Vec3 p;
  for (std::size_t i = 0; i < v.size(); ++i) p += v[i] * m.mass[i];
  return p;
}

// Sums of the forces and their torques about the origin, and their power, at state (x, v).
struct ForceSums {
  Vec3 force, torque;
  double power = 0.0, scale = 0.0;  // scale: sum |f_i| (for tolerances)
};
ForceSums sums(const World& world, const std::vector<Vec3>& x, const std::vector<Vec3>& v) {
  std::vector<Vec3> f(x.size());
  world.computeForces(x.data(), v.data(), 0.0, f.data());
  ForceSums s;
  for (std::size_t i = 0; i < x.size(); ++i) {
    s.force += f[i];
    s.torque += cross(x[i], f[i]);
    s.power += dot(f[i], v[i]);
    s.scale += length(f[i]);
  }
  return s;
}

TEST(DeformationDamping, RigidMotionFeelsNoForce) {
  // A sphere at its rest shape moving rigidly (translation plus spin about an axis away from
  // its centre): struts, hinges and the deformation damping all give zero, to rounding.
  Model model = sphereModel(makeIcosphere(1.0, 2), 0.05);
  World world(model, Integrator::RK4, 1e-3);
  std::vector<Vec3> x = world.model().restPosition, v(x.size());
  const Vec3 velocity{0.3, -2.0, 1.1}, spin{1.5, 4.0, -2.5}, pivot{2.0, -1.0, 0.5};
  for (std::size_t i = 0; i < x.size(); ++i) x[i] += Vec3{10.0, 5.0, -3.0}, v[i] = velocity + cross(spin, x[i] - pivot);
  std::vector<Vec3> f(x.size());
  world.computeForces(x.data(), v.data(), 0.0, f.data());
  double largest = 0.0, typical = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    largest = std::max(largest, length(f[i]));
    typical += world.model().mass[i] * length(v[i]) * world.model().bodies[0].deformationDamping;
  }
  EXPECT_LT(largest, 1e-11 * typical);
  EXPECT_EQ(world.forceStages().back(), ForceStage::Deformation);
}

TEST(DeformationDamping, KeepsMomentumAndAngularMomentumAndOnlyTakesEnergy) {
  Model model = sphereModel(makeIcosphere(1.0, 2), 0.05);
  World world(model, Integrator::RK4, 1e-3);
  std::vector<Vec3> x = world.model().restPosition, v(x.size());
  uint64_t seed = 7;
  auto next = [&] {  // a fixed pseudo-random sequence in [-1, 1)
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(seed >> 11) / 4503599627370496.0 - 1.0;
  };
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] += Vec3{next(), next(), next()} * 0.05;  // deformed too: the springs push
    v[i] = Vec3{next(), next(), next()};
  }
  const ForceSums s = sums(world, x, v);
  EXPECT_LT(length(s.force), 1e-12 * s.scale);
  EXPECT_LT(length(s.torque), 1e-12 * s.scale);
  // At the rest shape the springs exert nothing, so the power there is the damping's alone.
  const ForceSums atRest = sums(world, world.model().restPosition, v);
  EXPECT_LT(atRest.power, 0.0);
}

TEST(DeformationDamping, EveryDeformationDecaysAtTheStatedRate) {
  // Springs as good as off (a stretch period of 1e5 s, no hinges): a deformation velocity
  // falls as exp(-2 t / T), and the rigid part of the motion is kept. (No spin: with nothing
  // holding the vertices, a spinning body flies apart, which is a deformation of its own.)
  BodyDesc desc;
  desc.mesh = makeIcosphere(1.0, 2);
  desc.mass = 2.0;
  desc.material = MaterialModel::Body;
  desc.stretchPeriod = 1e5;
  desc.bendPeriod = 0.0;
  desc.deformationDecay = 0.1;
  Model model;
  model.gravity = {};
  addBody(model, desc);
  World world(model, Integrator::RK4, 1e-4);
  std::vector<Vec3> x = world.model().restPosition, v(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    v[i] = Vec3{0.2, 0.0, -0.1} + Vec3{x[i].x, -2 * x[i].y, x[i].z} * 0.3;
  }
  const Vec3 p0 = momentumOf(world.model(), v);
  world.setState(x, v);
  auto deformationSpeed = [&] {  // mass-weighted RMS of v - v_rigid
    MassMoments m = massMoments(world.model(), 0, x.size(), Vec3{}, world.positions().data(),
                                world.velocities().data());
    const RigidMotion r = rigidMotion(m, Vec3{});
    double sum = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      sum += world.model().mass[i] * lengthSquared(world.velocities()[i] - r.at(world.positions()[i]));
    }
    return std::sqrt(sum / m.mass);
  };
  const double start = deformationSpeed();
  for (int s = 0; s < 2000; ++s) world.step();  // 0.2 s = 2 T
  // Without springs the velocity itself decays at c = 2 / T; an oscillation's amplitude decays
  // at c / 2 = 1 / T (the seed's decay time: the amplitude falls by e in T).
  EXPECT_NEAR(deformationSpeed() / start, std::exp(-4.0), 0.01 * std::exp(-4.0));
  const Vec3 p1 = momentumOf(world.model(), world.velocities());
  EXPECT_LT(length(p1 - p0), 1e-12 * length(p0));
}

// The moduli mean what scenes/README.md says: an equal stretch e of the whole body stores
// 1/2 Y e^2 per unit area (exactly, at any resolution), and a flat sheet bent into a cylinder
// of radius R stores 1/2 D / R^2 per unit area (in the limit of fine equilateral triangles, in
// any direction).
TEST(BodyMaterial, EqualStretchStoresHalfYStrainSquaredPerArea) {
  for (int subdivisions : {1, 3}) {
    const TriMesh mesh = makeIcosphere(1.0, subdivisions);
    Model model = sphereModel(mesh, 0.1);
    World world(model, Integrator::RK4, 1e-3);
    const double e = 0.01;
    std::vector<Vec3> x = world.model().restPosition;
    for (Vec3& p : x) p = p * (1.0 + e);  // every edge longer by e, every angle kept
    world.setState(x, std::vector<Vec3>(x.size()));
    double area = 0.0;
    for (const Triangle& t : mesh.triangles) {
      area += 0.5 * length(cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]));
    }
    const double expected = 0.5 * world.model().bodies[0].membraneModulus * e * e * area;
    EXPECT_NEAR(measureBody(world, 0).elastic, expected, 1e-9 * expected) << subdivisions;
  }
}

TEST(BodyMaterial, BendingToRadiusRStoresHalfDOverRSquaredPerArea) {
  // A flat sheet of equilateral triangles (side a) in the xz plane, rolled about an axis
  // along z, then about one along x: the hinges' energy per unit area against 1/2 D / R^2.
  const int n = 48;
  const double a = 0.05, R = 1.0;
  TriMesh sheet;
  const double h = a * std::sqrt(3.0) / 2.0;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) sheet.positions.push_back({i * a + (j % 2) * a / 2, 0.0, j * h});
  }
  auto id = [&](int i, int j) { return static_cast<uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {  // one winding throughout (normals along -y)
    for (int i = 0; i < n; ++i) {
      if (j % 2 == 0) {
        sheet.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        sheet.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        sheet.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        sheet.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      }
    }
  }
  BodyDesc desc;
  desc.mesh = sheet;
  desc.mass = 1.0;
  desc.material = MaterialModel::Body;
  Model model;
  addBody(model, desc);
  const double D = model.bodies[0].bendingModulus;
  // The area the hinges cover: each hinge its two faces' thirds (A_1 + A_2) / 3, the area one
  // edge stands for in a triangulation (the sheet's border rows have no hinges of their own).
  double covered = 0.0;
  const auto faceArea = [&](const Vec3& p, const Vec3& q, const Vec3& r) { return 0.5 * length(cross(q - p, r - p)); };
  for (const Hinge& hg : model.hinges) {
    const std::vector<Vec3>& x0 = model.restPosition;
    covered += (faceArea(x0[hg.v[0]], x0[hg.v[1]], x0[hg.v[2]]) + faceArea(x0[hg.v[0]], x0[hg.v[1]], x0[hg.v[3]])) / 3.0;
  }
  const double width = n * a, depth = n * h;
  for (int axis : {2, 0}) {  // roll about z (bending along x), then about x (along z)
    World world(model, Integrator::RK4, 1e-3);
    std::vector<Vec3> x = world.model().restPosition;
    for (Vec3& p : x) {
      const double s = axis == 2 ? p.x - width / 2 : p.z - depth / 2;  // arc length across the roll
      const double along = R * std::sin(s / R), up = R * (1.0 - std::cos(s / R));
      p = axis == 2 ? Vec3{along, up, p.z} : Vec3{p.x, up, along};
    }
    world.setState(x, std::vector<Vec3>(x.size()));
    // Struts are stretched a little by the map's rounding only; count the hinges alone.
    double hingeEnergy = 0.0;
    for (const Hinge& hg : world.model().hinges) {
      HingeGeometry g;
      ASSERT_TRUE(hingeGeometry(x[hg.v[0]], x[hg.v[1]], x[hg.v[2]], x[hg.v[3]], g));
      const double d = g.theta - hg.restAngle;
      hingeEnergy += 0.5 * hg.stiffness * d * d;
    }
    EXPECT_NEAR(hingeEnergy / covered, 0.5 * D / (R * R), 0.05 * 0.5 * D / (R * R)) << "axis " << axis;
  }
}

// One sphere mesh of the resolution study, dropped and set ringing with the same keys.
struct Behaviour {
  double lowestVolume = 1.0;  // relative to the mesh's own rest volume
  double flattening = 0.0;    // largest 1 - height / rest height
  double period = 0.0;        // of the lowest (ellipsoidal) oscillation, free of gravity [s]
};

std::string sphereKeys(const std::string& shape, int subdivisions) {
  return "shape = \"" + shape + "\"\nsubdivisions = " + std::to_string(subdivisions) + "\nradius = 1.0\nmass = 1.0\n";
}

World worldFor(const std::string& text) {
  const SceneDesc scene = parseScene(text, "/virtual/resolution.toml");
  Model model = buildModel(scene);
  const StabilityReport r = estimateStability(model, model.restPosition, scene.integrator, scene.duration);
  const double dt = scene.dt / safeSubsteps(scene.dt, r.dtMax, kImpactMargin);
  World world(std::move(model), scene.integrator, dt);
  world.setThreads(2);
  return world;
}

double heightOf(const World& world) {
  double lo = INFINITY, hi = -INFINITY;
  for (const Vec3& p : world.positions()) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  return hi - lo;
}

Behaviour behaviour(const std::string& shape, int subdivisions) {
  Behaviour b;
  {
    // Dropped from 2 m onto the ground, through the impact and the rebound.
    World world = worldFor("[[body]]\n" + sphereKeys(shape, subdivisions) + "position = [0.0, 3.0, 0.0]\n[[plane]]\n");
    const double restHeight = heightOf(world), restVolume = world.model().bodies[0].restVolume;
    while (world.time() < 0.9) {  // landing at 0.64 s, deepest at about 0.75 s
      world.step();
      b.lowestVolume = std::min(b.lowestVolume, measureBody(world, 0).volume / restVolume);
      b.flattening = std::max(b.flattening, 1.0 - heightOf(world) / restHeight);
    }
  }
  {
    // Free of gravity, given the velocity of its lowest shape mode (an ellipsoid stretching
    // along y while it narrows in x and z, v = a (x, -2y, z), free of divergence): the period
    // of its height's oscillation, from the first to the third maximum over two periods.
    World world = worldFor("[environment]\ngravity = [0.0, 0.0, 0.0]\n[[body]]\n" + sphereKeys(shape, subdivisions));
    std::vector<Vec3> v(world.positions().size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Vec3& p = world.positions()[i];
      v[i] = Vec3{p.x, -2.0 * p.y, p.z} * 0.2;
    }
    world.setState(world.positions(), v);
    std::vector<double> maxima;
    double before2 = heightOf(world), before1 = before2;
    while (world.time() < 3.0 && maxima.size() < 3) {
      world.step();
      const double h = heightOf(world);
      if (before1 > before2 && before1 >= h) maxima.push_back(world.time() - world.dt());
      before2 = before1, before1 = h;
    }
    if (maxima.size() == 3) b.period = (maxima[2] - maxima[0]) / 2.0;
  }
  return b;
}

void expectWithin(double value, double reference, double tolerance, const std::string& what) {
  EXPECT_NEAR(value / reference, 1.0, tolerance) << what << ": " << value << " against " << reference;
}

TEST(BodyMaterial, ASphereBehavesTheSameAtEveryResolution) {
  // The same keys (mass and radius only: the material's defaults) on icospheres of 162, 642 and
  // 2562 vertices and octahedron spheres of 146 and 678: lowest volume, largest flattening and
  // the period of the lowest oscillation agree within 5% from about 640 vertices up and within
  // 10% at about 150. SPRINGY_RESOLUTION_FULL=1 adds octahedron spheres of 2502 and 10002 and
  // the icosphere of 10242 vertices (an hour on two cores; docs/benchmarks.md has the numbers).
  struct Mesh {
    std::string shape;
    int subdivisions;
    int vertices;
  };
  std::vector<Mesh> meshes = {{"icosphere", 2, 162},   {"octahedron_sphere", 6, 146}, {"icosphere", 3, 642},
                              {"octahedron_sphere", 13, 678}, {"icosphere", 4, 2562}};
  if (std::getenv("SPRINGY_RESOLUTION_FULL")) {
    meshes.push_back({"octahedron_sphere", 25, 2502});
    meshes.push_back({"icosphere", 5, 10242});
    meshes.push_back({"octahedron_sphere", 50, 10002});
  }
  std::vector<Behaviour> results;
  for (const Mesh& m : meshes) {
    results.push_back(behaviour(m.shape, m.subdivisions));
    const Behaviour& b = results.back();
    std::printf("%-18s %6d vertices: lowest volume %.4f, flattening %.4f, period %.4f s\n", m.shape.c_str(),
                m.vertices, b.lowestVolume, b.flattening, b.period);
    ASSERT_GT(b.period, 0.0) << m.shape << " " << m.vertices << ": no oscillation found";
  }
  // The reference: the finest icosphere run.
  std::size_t ref = 0;
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    if (meshes[k].shape == "icosphere") ref = k;
  }
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const double tolerance = meshes[k].vertices < 400 ? 0.10 : 0.05;
    const std::string what = meshes[k].shape + " " + std::to_string(meshes[k].vertices);
    expectWithin(results[k].lowestVolume, results[ref].lowestVolume, tolerance, what + " lowest volume");
    expectWithin(results[k].flattening, results[ref].flattening, tolerance, what + " flattening");
    expectWithin(results[k].period, results[ref].period, tolerance, what + " period");
  }
  // And the defaults hold a ball's shape through the drop.
  for (const Behaviour& b : results) EXPECT_GT(b.lowestVolume, 0.85);
}

}  // namespace
}  // namespace springy

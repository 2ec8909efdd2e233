// Integrators and whole-body dynamics: conservation laws, convergence orders, free fall,
// mass distribution, determinism.
#include <gtest/gtest.h>

#include <cmath>

#include "fixtures.h"
#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/monitor.h"
#include "sim/shapes.h"

#include <algorithm>

namespace springy {
namespace {

constexpr Integrator kAll[] = {Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::VelocityVerlet,
                               Integrator::Leapfrog, Integrator::RK4};

Model ballModel(Vec3 gravity, double strutDecay, double hingeDecay, double squash) {
  Model model;
  model.gravity = gravity;
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = makeIcosphere(1.0, 2);
  desc.mass = 3.0;
  desc.strutPeriod = 0.05;
  desc.strutDecay = strutDecay;
  desc.hingePeriod = 0.3;
  desc.hingeDecay = hingeDecay;
  addBody(model, desc);
  // Start deformed (and hence with elastic energy) by squashing the rest shape.
  for (Vec3& p : model.restPosition) p.y *= squash;
  return model;
}

TEST(Mass, AngleWeightedAreaConservesTotalMass) {
  for (const TriMesh& mesh : {makeOctahedronSphere(6.0, 6), makeCube(4.0, 3), makeJelly(8.5, 10, 8, 8, 40)}) {
    Model model;
    BodyDesc desc;
    desc.name = "b";
    desc.mesh = mesh;
    desc.mass = 8.0;
    addBody(model, desc);
    double total = 0.0;
    for (double m : model.mass) total += m;
    EXPECT_NEAR(total, 8.0, 1e-12);
    // Shares equal the surface area: a cube of side 4 has area 96.
    double area = 0.0;
    for (double a : angleWeightedAreas(mesh)) area += a;
    double faceArea = 0.0;
    for (const Triangle& t : mesh.triangles) {
      faceArea += 0.5 * length(cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]));
    }
    EXPECT_NEAR(area, faceArea, 1e-9 * faceArea);
  }
}

TEST(Shapes, CountsVolumesAndTopPole) {
  const TriMesh octa = makeOctahedronSphere(6.0, 6);
  EXPECT_EQ(octa.positions.size(), 4u * 36u + 2u);
  EXPECT_EQ(octa.positions[0], (Vec3{0, 6, 0}));
  EXPECT_EQ(makeIcosphere(1.0, 2).positions.size(), 162u);
  EXPECT_EQ(makeCube(2.0, 1).positions.size(), 8u);
  EXPECT_NEAR(signedVolume(makeCube(2.0, 3).positions, makeCube(2.0, 3).triangles), 8.0, 1e-12);
  const TriMesh tet = makeTetrahedron(1.0);
  EXPECT_NEAR(signedVolume(tet.positions, tet.triangles), 1.0 / (6 * std::sqrt(2.0)), 1e-12);
  // Spheres approach 4/3 pi r^3 from below as they are refined.
  const double sphere = 4.0 / 3.0 * kPi * 216.0;
  const double v6 = signedVolume(octa.positions, octa.triangles);
  EXPECT_GT(v6, 0.9 * sphere);
  EXPECT_LT(v6, sphere);
}

class EachIntegrator : public ::testing::TestWithParam<Integrator> {};

TEST_P(EachIntegrator, MomentumIsConservedWithoutExternalForces) {
  World world(ballModel({}, 0.05, 0.5, 0.7), GetParam(), 2e-4);
  std::vector<Vec3> v(world.positions().size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = Vec3{0.3, -0.1, 0.2} + cross(Vec3{0.5, 1.0, -0.4}, world.positions()[i]);
  world.setState(world.positions(), v);
  const BodyMeasures start = measureBody(world, 0);
  for (int s = 0; s < 2000; ++s) world.step();
  const BodyMeasures end = measureBody(world, 0);
  ASSERT_TRUE(end.finite);
  const double p = length(start.momentum), l = length(start.angularMomentum);
  EXPECT_LT(length(end.momentum - start.momentum), 1e-12 * p);
  // Angular momentum: the forces have zero net torque, so every scheme that updates positions
  // with a velocity the forces produced keeps it to round-off. Explicit Euler does not, even
  // in exact arithmetic: L gains dt^2 sum m v x a per step. Its drift is bounded instead.
  const double drift = length(end.angularMomentum - start.angularMomentum);
  if (GetParam() == Integrator::ExplicitEuler) {
    EXPECT_LT(drift, 1e-2 * l);
    EXPECT_GT(drift, 1e-9 * l);  // documents that the loss is real, not round-off
  } else {
    EXPECT_LT(drift, 1e-9 * l);
  }
}

INSTANTIATE_TEST_SUITE_P(All, EachIntegrator, ::testing::ValuesIn(kAll),
                         [](const auto& p) { return std::string(integratorName(p.param)); });

TEST(Energy, SymplecticSchemesKeepEnergyBoundedWithoutDamping) {
  for (Integrator integrator : {Integrator::SymplecticEuler, Integrator::VelocityVerlet, Integrator::Leapfrog}) {
    Model model = ballModel({}, 1e300, 1e300, 0.8);  // decay times so long there is no damping
    for (Strut& s : model.struts) s.damping = 0.0;
    for (Hinge& h : model.hinges) h.damping = 0.0;
    World world(std::move(model), integrator, 5e-4);
    const double e0 = measureBody(world, 0).total();
    ASSERT_GT(e0, 0.0);
    double lo = e0, hi = e0;
    for (int s = 0; s < 20000; ++s) {  // 10 s, about 200 strut periods
      world.step();
      if (s % 10 == 0) {
        const double e = measureBody(world, 0).total();
        lo = std::min(lo, e);
        hi = std::max(hi, e);
      }
    }
    const double e1 = measureBody(world, 0).total();
    EXPECT_LT((hi - lo) / e0, 0.1) << integratorName(integrator);
    EXPECT_LT(std::fabs(e1 - e0) / e0, 0.1) << integratorName(integrator);
  }
  // Explicit Euler is not symplectic: the same run gains energy.
  Model model = ballModel({}, 1e300, 1e300, 0.8);
  for (Strut& s : model.struts) s.damping = 0.0;
  for (Hinge& h : model.hinges) h.damping = 0.0;
  World euler(std::move(model), Integrator::ExplicitEuler, 5e-4);
  const double e0 = measureBody(euler, 0).total();
  for (int s = 0; s < 2000; ++s) euler.step();
  EXPECT_GT(measureBody(euler, 0).total(), 1.1 * e0);
}

TEST(Energy, DampingNeverAddsEnergy) {
  World world(ballModel({}, 0.02, 0.1, 0.7), Integrator::RK4, 2e-4);
  double previous = measureBody(world, 0).total();
  for (int s = 0; s < 5000; ++s) {
    world.step();
    const double e = measureBody(world, 0).total();
    ASSERT_LE(e, previous * (1 + 1e-9)) << "step " << s;
    previous = e;
  }
}

TEST(Energy, MonitorCatchesEnergyGainedAfterItWasLost) {
  // A squashed, damped ball loses most of its elastic energy; then energy is put back (its
  // velocities set to a kick worth a fifth of the start energy). The total is still far below
  // the start, which an "above the start" test would accept; the monitor measures from the
  // lowest total so far and stops the run, naming when that lowest was. The stability study's
  // bounded-energy criterion (energyFromLowest = false) does not.
  World world(ballModel({}, 0.02, 0.1, 0.7), Integrator::RK4, 2e-4);
  Monitor monitor(world);
  MonitorLimits fromStart;
  fromStart.energyFromLowest = false;
  Monitor classic(world, fromStart);
  const double start = measureBody(world, 0).total();
  for (int s = 0; s < 5000; ++s) {
    world.step();
    if (s % 50 == 0) {
      ASSERT_FALSE(monitor.check(world));
      ASSERT_FALSE(classic.check(world));
    }
  }
  const double low = measureBody(world, 0).total();
  ASSERT_LT(low, 0.5 * start);
  const double kick = std::sqrt(2.0 * 0.2 * start / 3.0);  // 3 kg: kinetic energy 0.2 start
  std::vector<Vec3> v(world.positions().size(), Vec3{kick, 0.0, 0.0});
  world.setState(world.positions(), v, world.time());
  ASSERT_LT(measureBody(world, 0).total(), start);
  const std::optional<Failure> failure = monitor.check(world);
  ASSERT_TRUE(failure);
  EXPECT_NE(failure->message.find("its total energy rose from"), std::string::npos) << failure->message;
  EXPECT_NE(failure->message.find("(its lowest, at t = 0.9902 s)"), std::string::npos) << failure->message;  // the last check
  EXPECT_FALSE(classic.check(world));
}

// Damped oscillator x'' = -w^2 x - 2 z w x', one free mass on a strut with the other end
// pinned: the closed form is the reference.
double oscillatorError(Integrator integrator, double dt) {
  const double m = 1.0, k = 40.0, d = 0.6, L = 1.0, x0 = 0.1, tEnd = 2.0;
  World world(test::strutModel(m, m, L, k, d, true), integrator, dt);
  std::vector<Vec3> x = world.positions();
  x[1].x += x0;
  world.setState(x, world.velocities());
  const int steps = static_cast<int>(std::lround(tEnd / dt));
  for (int s = 0; s < steps; ++s) world.step();
  const double w0 = std::sqrt(k / m), gamma = d / (2 * m), wd = std::sqrt(w0 * w0 - gamma * gamma);
  const double exact = x0 * std::exp(-gamma * tEnd) * (std::cos(wd * tEnd) + gamma / wd * std::sin(wd * tEnd));
  return std::fabs(world.positions()[1].x - L - exact);
}

TEST(Convergence, MeasuredOrdersMatchTheory) {
  const std::pair<Integrator, double> expected[] = {{Integrator::ExplicitEuler, 1.0}, {Integrator::SymplecticEuler, 1.0},
                                                    {Integrator::VelocityVerlet, 2.0}, {Integrator::Leapfrog, 2.0},
                                                    {Integrator::RK4, 4.0}};
  for (auto [integrator, order] : expected) {
    // Least-squares slope of log(error) against log(dt) over a ladder of halvings, in the
    // asymptotic range of each method (RK4 stays above round-off).
    const double dt0 = integrator == Integrator::RK4 ? 1e-2 : (order == 1.0 ? 1e-3 : 4e-3);
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const int n = 4;
    for (int i = 0; i < n; ++i) {
      const double dt = dt0 / std::pow(2.0, i);
      const double lx = std::log(dt), ly = std::log(oscillatorError(integrator, dt));
      sx += lx; sy += ly; sxx += lx * lx; sxy += lx * ly;
    }
    const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    EXPECT_NEAR(slope, order, 0.2) << integratorName(integrator);
  }
}

TEST(FreeFall, FollowsTheBallisticParabola) {
  // A free body's centre of mass moves as x0 + v0 t + 1/2 g t^2 whatever the springs do.
  for (Integrator integrator : kAll) {
    Model model = ballModel({0, -9.81, 0}, 0.05, 0.5, 0.8);
    World world(std::move(model), integrator, 1e-3);
    std::vector<Vec3> v(world.positions().size(), Vec3{1.5, 4.0, -0.5});
    world.setState(world.positions(), v);
    const Vec3 c0 = measureBody(world, 0).centroid;
    for (int s = 0; s < 1000; ++s) world.step();
    const double t = world.time();
    const Vec3 expected = c0 + Vec3{1.5, 4.0, -0.5} * t + Vec3{0, -9.81, 0} * (0.5 * t * t);
    const double tol = integrator == Integrator::ExplicitEuler || integrator == Integrator::SymplecticEuler
                           ? 0.5 * 9.81 * t * 1e-3 * 1.01  // first order: error g t dt / 2
                           : 1e-9;
    EXPECT_LT(length(measureBody(world, 0).centroid - expected), tol) << integratorName(integrator);
  }
}

TEST(Determinism, SameRunGivesBitIdenticalState) {
  auto run = [] {
    Model model = ballModel({0, -9.81, 0}, 0.05, 0.5, 0.8);
    model.colliders.planes.push_back({{0, -1.2, 0}, {0, 1, 0}, {0.6, 0.3}});
    World world(std::move(model), Integrator::RK4, 1e-3);
    for (int s = 0; s < 1500; ++s) world.step();
    return stateHash(world);
  };
  const uint64_t a = run(), b = run();
  EXPECT_EQ(a, b);
}

TEST(Stages, ASceneAssemblesOnlyTheStagesItUses) {
  Model model = ballModel({}, 0.05, 0.5, 1.0);
  World bare(model, Integrator::RK4, 1e-3);
  EXPECT_EQ(bare.forceStages(), (std::vector<ForceStage>{ForceStage::Struts, ForceStage::Hinges}));
  EXPECT_FALSE(bare.collides());
  model.gravity = {0, -9.81, 0};
  model.drag = 0.1;
  model.wind = Wind{};
  model.wind->pressure = 1.0;
  model.colliders.planes.push_back({{0, -2, 0}, {0, 1, 0}, {}});
  World full(model, Integrator::RK4, 1e-3);
  EXPECT_EQ(full.forceStages(), (std::vector<ForceStage>{ForceStage::Gravity, ForceStage::Drag, ForceStage::Wind,
                                                         ForceStage::Struts, ForceStage::Hinges}));
  EXPECT_TRUE(full.collides());
  // Gas is a stage only for a body that holds it.
  Model balloon = ballModel({}, 0.05, 0.5, 1.0);
  balloon.bodies[0].gasPressure = 100.0;
  EXPECT_EQ(World(balloon, Integrator::RK4, 1e-3).forceStages(),
            (std::vector<ForceStage>{ForceStage::Struts, ForceStage::Hinges, ForceStage::Gas}));
  // The legacy all-pairs model has no hinge stage.
  Model legacy;
  BodyDesc cube;
  cube.name = "cube";
  cube.mesh = makeCube(10.0);
  cube.model = SpringModel::AllPairs;
  cube.mass = 8;
  addBody(legacy, cube);
  EXPECT_EQ(legacy.struts.size(), 28u);
  EXPECT_TRUE(legacy.hinges.empty());
}

}  // namespace
}  // namespace springy

namespace springy {
namespace {

TEST(Drag, FallingBodyApproachesTerminalVelocityGOverC) {
  // m dv/dt = m g - c m v  =>  v(t) = (g / c)(1 - exp(-c t)).
  Model model = test::vertexModel({}, {}, {0, -9.81, 0}, 2.0);
  model.drag = 0.5;
  World world(std::move(model), Integrator::RK4, 1e-3);
  for (int s = 0; s < 4000; ++s) world.step();
  const double t = world.time(), expected = -9.81 / 0.5 * (1 - std::exp(-0.5 * t));
  EXPECT_NEAR(world.velocities()[0].y, expected, 1e-9);
}

TEST(Wind, SteadyWindCarriesADraggedBodyToTheAirVelocity) {
  Model model = test::vertexModel({}, {}, {}, 2.0);
  model.drag = 2.0;
  model.wind = Wind{};
  model.wind->velocity = {3.0, 0.0, -1.0};
  World world(std::move(model), Integrator::RK4, 1e-3);
  for (int s = 0; s < 5000; ++s) world.step();  // 10 time constants
  const Vec3 expected = Vec3{3.0, 0.0, -1.0} * (1 - std::exp(-2.0 * world.time()));
  EXPECT_LT(length(world.velocities()[0] - expected), 1e-9);
}

TEST(Wind, GustsRepeatForASeedAndDifferBetweenSeeds) {
  SceneDesc scene;
  scene.wind = Wind{};
  scene.wind->velocity = {5, 0, 0};
  scene.wind->gustStrength = 0.5;
  BodyDesc body;
  body.name = "b";
  body.mesh = makeTetrahedron(1.0);
  scene.bodies = {body};
  scene.view.bodies = {Material{}};
  auto gusts = [&](uint64_t seed) {
    scene.wind->seed = seed;
    const Model model = buildModel(scene);
    std::vector<double> w;
    for (int k = 0; k < 50; ++k) w.push_back(model.wind->airVelocity(0.1 * k).x);
    return w;
  };
  EXPECT_EQ(gusts(7), gusts(7));
  EXPECT_NE(gusts(7), gusts(8));
  const std::vector<double> w = gusts(7);
  const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
  EXPECT_GT(*hi - *lo, 1.0);  // the gusts are real: the air speed varies by more than 20%
  EXPECT_GT(*lo, 0.0);        // around the base velocity, not reversing it
}

TEST(Wind, PressurePushesAFaceTurnedIntoTheWindOnly) {
  // One triangle facing +x, wind along -x: pushed along -x with c A (w . n) n.
  Model model;
  model.gravity = {};
  model.mass = {1, 1, 1};
  model.invMass = {1, 1, 1};
  model.restPosition = {{0, 0, 0}, {0, 1, 0}, {0, 0, -1}};
  model.initialVelocity = std::vector<Vec3>(3);
  model.body = {0, 0, 0};
  model.faces = {{0, 2, 1}};
  BodyInfo info;
  info.name = "sail";
  info.vertexCount = 3;
  info.faceCount = 1;
  model.bodies = {info};
  model.wind = Wind{};
  model.wind->velocity = {-4.0, 0, 0};
  model.wind->pressure = 0.5;
  const Vec3 n = normalized(cross(model.restPosition[2] - model.restPosition[0], model.restPosition[1] - model.restPosition[0]));
  ASSERT_NEAR(n.x, 1.0, 1e-12);
  World world(model, Integrator::RK4, 1e-3);
  std::vector<Vec3> f(3);
  world.computeForces(world.positions().data(), world.velocities().data(), 0.0, f.data());
  const double area = 0.5;
  Vec3 total = f[0] + f[1] + f[2];
  EXPECT_NEAR(total.x, 0.5 * area * -4.0, 1e-12);
  EXPECT_NEAR(length(total - Vec3{total.x, 0, 0}), 0.0, 1e-12);
  // Turned away from the wind (leeward): no force.
  model.wind->velocity = {4.0, 0, 0};
  World leeward(model, Integrator::RK4, 1e-3);
  leeward.computeForces(leeward.positions().data(), leeward.velocities().data(), 0.0, f.data());
  EXPECT_EQ(f[0] + f[1] + f[2], Vec3{});
}

}  // namespace
}  // namespace springy

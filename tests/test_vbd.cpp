// Vertex block descent (sim/vbd.h): its colours are independent sets, converged it is the
// backward Euler step (the closed form of a damped strut; the Newton solver's step of a ball with
// struts, hinges and gas), it holds vertices on a collider, and it is stable far past the
// explicit limit.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "error_of.h"
#include "fixtures.h"
#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/force_stages.h"
#include "sim/implicit.h"
#include "sim/monitor.h"
#include "sim/shapes.h"
#include "sim/limits.h"
#include "sim/vbd.h"
#include "sim/world.h"

namespace springy {
namespace {

Model gasBall(int level, double strutPeriod, double hingePeriod, double volumePeriod) {
  Model model;
  model.gravity = {0, -9.81, 0};
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = makeIcosphere(0.5, level);
  desc.strutPeriod = strutPeriod;
  desc.strutDecay = 0.15;
  desc.hingePeriod = hingePeriod;
  desc.hingeDecay = 1.0;
  desc.volumePeriod = volumePeriod;
  addBody(model, desc);
  return model;
}

TEST(Vbd, ColoursAreIndependentSetsThatCoverEveryVertexOnce) {
  const Model model = gasBall(2, 0.015, 0.05, 0.01);
  const VbdSolver solver(model);
  std::vector<int> colourOf(model.vertexCount(), -1);
  for (std::size_t c = 0; c < solver.colours(); ++c) {
    std::size_t count;
    const uint32_t* list = solver.colour(c, count);
    for (std::size_t k = 0; k < count; ++k) {
      ASSERT_EQ(colourOf[list[k]], -1) << "vertex " << list[k] << " in two colours";
      colourOf[list[k]] = static_cast<int>(c);
    }
  }
  for (int c : colourOf) ASSERT_GE(c, 0);
  for (const Strut& s : model.struts) EXPECT_NE(colourOf[s.i], colourOf[s.j]);
  for (const Hinge& h : model.hinges) {
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) EXPECT_NE(colourOf[h.v[a]], colourOf[h.v[b]]);
    }
  }
  // Greedy on a mesh whose vertices have 5-6 neighbours (and hinges reaching the wing tips).
  EXPECT_LE(solver.colours(), 16u);
}

TEST(Vbd, ConvergedStepIsTheClosedFormBackwardEulerMap) {
  // At omega h = 6.5 (explicit steps are stable only below 2).
  test::expectTheClosedFormBackwardEulerMap(Integrator::Vbd, 0.2, kMaxIterations, 1e-10, 1e-10);
}

TEST(Vbd, ConvergedStepOfAGasBallWithHingesIsNewtonsBackwardEulerStep) {
  // The same fixed point as the Newton solver's, reached by sweeps: a ball squashed by a
  // quarter and spinning, one step of 10 ms (the gas's period, and 2/3 of the struts').
  Model model = gasBall(2, 0.015, 0.05, 0.01);
  std::vector<Vec3> x = model.restPosition, v(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i].y *= 0.75;
    v[i] = cross(Vec3{0, 0, 4.0}, x[i]) + Vec3{0.3, 0, 0};
  }
  const Forces forces(model);
  ImplicitSettings tight;
  tight.maxNewton = 40;
  tight.newtonTolerance = 1e-14;
  tight.velocityTolerance = 1e-14;
  tight.cgTolerance = 1e-14;
  tight.maxCg = 5000;
  ImplicitSolver newton(model, tight);
  std::vector<Vec3> xn = x, vn = v;
  newton.step(forces, xn, vn, 0.0, 0.01);
  VbdSolver vbd(model, 600);
  std::vector<Vec3> xb = x, vb = v;
  vbd.step(forces, xb, vb, 0.0, 0.01);
  double worst = 0.0, moved = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    worst = std::fmax(worst, length(xb[i] - xn[i]));
    moved = std::fmax(moved, length(xn[i] - x[i]));
  }
  EXPECT_GT(moved, 0.01);    // the step does something: up to cm
  EXPECT_LT(worst, 1e-9) << "largest difference " << worst << " m of a step that moves up to " << moved << " m";
  // The volume it tracks by sums of g . dx is the enclosed volume of where it ends.
  EXPECT_NEAR(enclosedVolume(model, 0, xb.data()), enclosedVolume(model, 0, xn.data()), 1e-12);
}

TEST(Vbd, UndampedEnergyNeverRisesAtStepsFarPastTheExplicitLimit) {
  // Converged, the step is backward Euler's, which only dissipates: a swinging hinge with stiff
  // struts at up to 0.3 s a step (k h^2 / m = 27 for the struts). The sweeps converge at a rate
  // set by k h^2 / m (Gauss-Seidel on a stiff block): at 1 s a step (k h^2 / m = 300) even 1000
  // sweeps leave a residual whose energy, near rest, rises by 1e-9 of itself.
  for (double h : {0.001, 0.01, 0.1, 0.3}) {
    World world(test::hingeModel(0.4, 5.0, 0.0, true, 300.0, 0.0), Integrator::Vbd, h);
    world.setIterations(kMaxIterations);
    world.setState(test::hingePositions(1.4), std::vector<Vec3>(4));
    double previous = measureBody(world, 0).total();
    for (int s = 0; s < 30; ++s) {
      world.step();
      const double e = measureBody(world, 0).total();
      ASSERT_LE(e, previous * (1 + 1e-9) + 1e-12) << "dt " << h << " step " << s;
      previous = e;
    }
  }
}

TEST(Vbd, BallDroppedOntoThePlaneAtALargeStepStaysAboveItAndKeepsItsVolume) {
  // 642 vertices, gas, struts of 15 ms at 4 ms a step (the explicit limit is about 1 ms here),
  // dropped from 0.5 m; 8 sweeps a step.
  Model model = gasBall(3, 0.015, 0.0, 0.01);
  for (Vec3& p : model.restPosition) p.y += 1.0;
  model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, {}});
  World world(std::move(model), Integrator::Vbd, 0.004);
  Monitor monitor(world);
  double lowest = 1.0, lowestY = 1.0;
  for (int s = 0; s < 300; ++s) {
    world.step();
    const auto failure = monitor.check(world);
    ASSERT_FALSE(failure) << failure->message;
    for (const Vec3& p : world.positions()) lowestY = std::fmin(lowestY, p.y);
    lowest = std::fmin(lowest, measureBody(world, 0).volume / world.model().bodies[0].restVolume);
  }
  EXPECT_GE(lowestY, -1e-9);
  EXPECT_GT(lowest, 0.95);
  EXPECT_LT(std::fabs(measureBody(world, 0).centroid.y - 0.5), 0.1);  // on the ground, round again
}

TEST(Vbd, AVertexHeldOnThePlaneBouncesWithItsArrivalSpeed) {
  // A vertex falls at 3 m/s onto a plane with restitution 0.6, 4 mm above it at a step of 10 ms:
  // the solve holds it on the surface, where only 0.4 m/s of its travel was left; restitution
  // must act on the 3 m/s + h g it arrived with, not on that remainder.
  Model model = vertexModel({0, 0.004, 0}, {0.5, -3.0, 0}, {0, -9.81, 0});
  model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, {0.6, 0.0}});
  const double h = 0.01;
  World world(std::move(model), Integrator::Vbd, h);
  world.step();
  EXPECT_NEAR(world.positions()[0].y, 0.0, 2e-6);  // on the surface (its skin)
  EXPECT_NEAR(world.velocities()[0].y, 0.6 * (3.0 + 9.81 * h), 1e-9);
  EXPECT_NEAR(world.velocities()[0].x, 0.5, 1e-9);  // no friction
}

TEST(Vbd, FrictionActsOnTheWholeWeightTheSurfaceCarries) {
  // A stiff cube (all pairs) sliding at 1 m/s on a plane with friction 0.5: each bottom corner
  // carries a quarter of the weight through the struts, so the cube slows at mu g, to 0.5095 m/s
  // at 0.1 s. Friction on the corners' own weight alone would leave 0.755 m/s; on their blocks'
  // free Newton step (which the stiff struts resist) it left 0.959. Measured: 0.471 at 10 ms a
  // step and closer at 5 ms (first order: the step's friction acts on its end velocity).
  double error[2];
  for (int k = 0; k < 2; ++k) {
    const double h = k == 0 ? 0.01 : 0.005;
    const SceneDesc scene = parseScene(R"(
[scene]
integrator = "vbd"
iterations = 30
[[body]]
shape = "cube"
size = 0.2
position = [0.0, 0.1, 0.0]
velocity = [1.0, 0.0, 0.0]
model = "all_pairs"
mass = 1.0
mass_distribution = "uniform"
strut_period = 0.02
strut_decay = 0.02
[[plane]]
restitution = 0.0
friction = 0.5
)",
                                       "/virtual/slide.toml");
    World world(buildModel(scene), scene.integrator, h);
    world.setIterations(scene.iterations);
    while (!world.reached(0.1)) world.step();
    error[k] = std::fabs(measureBody(world, 0).momentum.x - (1.0 - 0.5 * 9.81 * 0.1));  // mass 1 kg
  }
  EXPECT_LT(error[0], 0.045);
  EXPECT_LT(error[1], 0.6 * error[0]);
}

TEST(Vbd, SceneKeyAndErrors) {
  const SceneDesc scene = parseScene("[scene]\nintegrator = \"vbd\"\niterations = 12\n[[body]]\nshape = \"icosphere\"\n",
                                     "/virtual/vbd.toml");
  EXPECT_EQ(scene.integrator, Integrator::Vbd);
  EXPECT_EQ(scene.iterations, 12);
  const std::string e = test::errorOf([] { parseScene("[scene]\niterations = 0\n", "/virtual/bad.toml"); });
  EXPECT_NE(e.find("/virtual/bad.toml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("iterations"), std::string::npos) << e;
  // Any other integrator would ignore the sweeps: the key is refused where it stands.
  const std::string other = test::errorOf(
      [] { parseScene("[scene]\nintegrator = \"rk4\"\niterations = 4\n", "/virtual/rk4.toml"); });
  EXPECT_NE(other.find("/virtual/rk4.toml:3"), std::string::npos) << other;
  EXPECT_NE(other.find("integrator is rk4"), std::string::npos) << other;
}

}  // namespace
}  // namespace springy

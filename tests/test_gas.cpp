// The enclosed gas (sim/forces.h): its force is minus the gradient of its energy, its breathing
// mode has the period the scene asks for, the advisor's step limit for it is the measured one,
// energy is conserved with it, every integrator (backward Euler included) runs it, and it is
// what keeps a soft ball's volume on impact.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/forces.h"
#include "sim/implicit.h"
#include "sim/monitor.h"
#include "sim/shapes.h"
#include "sim/stability.h"
#include "sim/world.h"

namespace springy {
namespace {

double wobble(int i) { return std::sin(12.9898 * (i + 1) + 78.233); }
Vec3 perturb(int i) { return {wobble(3 * i), wobble(3 * i + 1), wobble(3 * i + 2)}; }

// A ball of radius 1 holding gas; springs as given (0: none), no gravity unless asked.
Model gasBall(int level, double volumePeriod, double strutStiffness, double hingePeriod, Vec3 gravity = {}) {
  Model model;
  model.gravity = gravity;
  BodyDesc desc;
  desc.name = "balloon";
  desc.mesh = makeIcosphere(1.0, level);
  desc.mass = 2.0;
  desc.strutStiffness = strutStiffness;
  desc.strutDamping = 0.0;
  desc.hingePeriod = hingePeriod;
  desc.hingeDecay = 0.0;
  desc.volumePeriod = volumePeriod;
  addBody(model, desc);
  return model;
}

// Positions displaced along M^-1 g (the gas's own direction) so that V = (1 + eps) V0 to first
// order: in the linearised dynamics the body then moves in that direction only.
std::vector<Vec3> breathingStart(const Model& model, double eps) {
  std::vector<Vec3> g(model.vertexCount());
  volumeGradient(model, model.bodies[0], model.restPosition.data(), g.data());
  double gMg = 0.0;
  for (std::size_t i = 0; i < g.size(); ++i) gMg += lengthSquared(g[i]) * model.invMass[i];
  const double scale = eps * model.bodies[0].restVolume / gMg;
  std::vector<Vec3> start = model.restPosition;
  for (std::size_t i = 0; i < g.size(); ++i) start[i] += g[i] * (scale * model.invMass[i]);
  return start;
}

TEST(Gas, ForceIsMinusTheGradientOfItsEnergy) {
  const Model model = gasBall(2, 0.05, 0.0, 0.0);
  const BodyInfo& body = model.bodies[0];
  std::vector<Vec3> x = model.restPosition;
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = x[i] * 0.93 + perturb(static_cast<int>(i)) * 0.04;
  const double volume = enclosedVolume(model, 0, x.data());
  ASSERT_LT(volume, 0.95 * body.restVolume);  // compressed: the gas pushes out
  const double p = gasOverpressure(body, volume);
  ASSERT_GT(p, 0.0);
  std::vector<Vec3> f(x.size()), areaVectors(model.faces.size());
  sixVolume(model, 0, static_cast<uint32_t>(model.faces.size()), x[0], x.data(), areaVectors.data());
  applyGasPressure(model, &p, vertexFaces(model), areaVectors.data(), 0, x.size(), f.data());
  const double h = 1e-6;
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      std::vector<Vec3> xp = x, xm = x;
      xp[i][c] += h;
      xm[i][c] -= h;
      const double slope =
          (gasEnergy(body, enclosedVolume(model, 0, xp.data())) - gasEnergy(body, enclosedVolume(model, 0, xm.data()))) /
          (2 * h);
      worst = std::fmax(worst, std::fabs(f[i][c] + slope));
      scale = std::fmax(scale, std::fabs(f[i][c]));
    }
  }
  EXPECT_LT(worst, 1e-7 * scale) << "largest force component " << scale;
  // The gas pushes outward and exerts no net force or torque on the body.
  Vec3 total, torque;
  for (std::size_t i = 0; i < x.size(); ++i) total += f[i], torque += cross(x[i], f[i]);
  EXPECT_LT(length(total), 1e-12 * scale * static_cast<double>(x.size()));
  EXPECT_LT(length(torque), 1e-12 * scale * static_cast<double>(x.size()));
}

// sixVolume takes four faces at a time (sim/lanes.h) and the rest one by one: over every range
// length and start, each face's N is bit-identical to the cross product of its edges, and the
// sum matches the face-by-face sum to round-off.
TEST(Gas, SixVolumeOfAnyFaceRangeIsTheSumOfItsFaces) {
  const Model model = gasBall(1, 0.05, 0.0, 0.0);
  std::vector<Vec3> x = model.restPosition;
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = x[i] * 0.9 + perturb(static_cast<int>(i)) * 0.05;
  const Vec3 o = x[3];
  const uint32_t faces = static_cast<uint32_t>(model.faces.size());
  for (uint32_t begin : {0u, 1u, 2u, 3u, 5u, 17u}) {
    for (uint32_t count = 0; count <= 13 && begin + count <= faces; ++count) {
      std::vector<Vec3> n(faces, Vec3{-1, -1, -1});
      const double six = sixVolume(model, begin, begin + count, o, x.data(), n.data());
      double expected = 0.0, magnitude = 0.0;
      for (uint32_t f = begin; f < begin + count; ++f) {
        const Triangle& t = model.faces[f];
        const Vec3 cr = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]);
        EXPECT_EQ(n[f], cr) << "face " << f << " of [" << begin << ", " << begin + count << ")";
        expected += dot(x[t[0]] - o, cr);
        magnitude += std::fabs(dot(x[t[0]] - o, cr));
      }
      EXPECT_NEAR(six, expected, 1e-15 * magnitude) << "[" << begin << ", " << begin + count << ")";
      EXPECT_EQ(sixVolume(model, begin, begin + count, o, x.data(), nullptr), six);  // the same sum without N
      if (begin > 0) {
        EXPECT_EQ(n[begin - 1], (Vec3{-1, -1, -1}));  // nothing written outside the range
      }
      if (begin + count < faces) {
        EXPECT_EQ(n[begin + count], (Vec3{-1, -1, -1}));
      }
    }
  }
}

TEST(Gas, VolumeIsExactAndIndependentOfWhereTheBodyIs) {
  // A cube of side 2: 8 m^3, wherever it is.
  Model model;
  BodyDesc desc;
  desc.name = "box";
  desc.mesh = makeCube(2.0, 3);
  desc.volumePeriod = 0.1;
  addBody(model, desc);
  std::vector<Vec3> x = model.restPosition;
  EXPECT_NEAR(enclosedVolume(model, 0, x.data()), 8.0, 1e-12);
  for (Vec3& p : x) p += Vec3{1e4, -3e3, 7e3};
  EXPECT_NEAR(enclosedVolume(model, 0, x.data()), 8.0, 1e-9);
  // Ideal gas: twice the pressure at half the volume, and no energy at rest.
  const BodyInfo& body = model.bodies[0];
  EXPECT_NEAR(gasOverpressure(body, 4.0) + body.gasPressure, 2 * body.gasPressure, 1e-9 * body.gasPressure);
  EXPECT_NEAR(gasEnergy(body, 8.0), 0.0, 1e-15 * body.gasPressure);
  EXPECT_GT(gasEnergy(body, 7.0), 0.0);
  EXPECT_GT(gasEnergy(body, 9.0), 0.0);
}

TEST(Gas, BreathingModeHasTheRequestedPeriod) {
  // Gas only (no springs): displaced along M^-1 g, the volume oscillates with volume_period.
  const double period = 0.05;
  World world(gasBall(3, period, 0.0, 0.0), Integrator::RK4, period / 400);
  const double v0 = world.model().bodies[0].restVolume;
  world.setState(breathingStart(world.model(), 1e-4), std::vector<Vec3>(world.model().vertexCount()));
  // Times at which V - V0 crosses zero upward, interpolated linearly.
  std::vector<double> upward;
  double previous = measureBody(world, 0).volume - v0;
  while (world.time() < 4.2 * period) {
    world.step();
    const double now = measureBody(world, 0).volume - v0;
    if (previous < 0.0 && now >= 0.0) upward.push_back(world.time() - world.dt() * now / (now - previous));
    previous = now;
  }
  ASSERT_GE(upward.size(), 3u);
  const double measured = (upward.back() - upward.front()) / static_cast<double>(upward.size() - 1);
  EXPECT_NEAR(measured, period, 1e-4 * period);
}

TEST(Gas, AdvisorsStepLimitIsTheMeasuredOne) {
  // The breathing mode is one eigenvalue, omega = 2 pi / P_V: symplectic Euler is stable for
  // omega dt < 2. The advisor says exactly that, and the run agrees on either side of it.
  const double period = 0.05, omega = 2 * kPi / period;
  const Model model = gasBall(3, period, 0.0, 0.0);
  const StabilityReport report = estimateStability(model, model.restPosition, Integrator::SymplecticEuler, 1.0);
  EXPECT_NEAR(report.bodies[0].omegaMax, omega, 1e-9 * omega);
  for (const double factor : {0.9, 1.1}) {
    World world(model, Integrator::SymplecticEuler, factor * 2.0 / omega);
    world.setState(breathingStart(model, 1e-4), std::vector<Vec3>(model.vertexCount()));
    const double v0 = model.bodies[0].restVolume;
    double largest = 0.0;
    for (int s = 0; s < 400; ++s) {
      world.step();
      largest = std::fmax(largest, std::fabs(measureBody(world, 0).volume - v0) / v0);
    }
    if (factor < 1.0) EXPECT_LT(largest, 3e-4) << "dt " << world.dt();
    else EXPECT_GT(largest, 1e-2) << "dt " << world.dt();
  }
}

TEST(Gas, EnergyWithTheGasIsConservedWithoutDamping) {
  // Struts, hinges and gas, squashed and let go: kinetic + springs + gas stays constant up to
  // RK4's error, which falls as dt^4 (a force that were not -grad E would leave an error that
  // does not fall with dt).
  double worst[2];
  for (int k = 0; k < 2; ++k) {
    Model model = gasBall(2, 0.02, 400.0, 0.1);
    std::vector<Vec3> start = model.restPosition;
    for (Vec3& p : start) p.y *= 0.8;
    const double dt = k == 0 ? 2e-4 : 1e-4;
    World world(std::move(model), Integrator::RK4, dt);
    world.setState(start, std::vector<Vec3>(start.size()));
    const BodyMeasures first = measureBody(world, 0);
    ASSERT_GT(gasEnergy(world.model().bodies[0], first.volume), 0.3 * first.elastic);  // the gas holds much of it
    worst[k] = 0.0;
    while (world.time() < 0.5 - 0.5 * dt) {
      world.step();
      worst[k] = std::fmax(worst[k], std::fabs(measureBody(world, 0).total() - first.total()) / first.total());
    }
    EXPECT_GT(measureBody(world, 0).kinetic, 0.05 * first.elastic);  // it moved
  }
  EXPECT_LT(worst[0], 1e-5);
  EXPECT_GT(worst[0] / worst[1], 12.0) << worst[0] << " at 0.2 ms, " << worst[1] << " at 0.1 ms";
}

TEST(Gas, KeepsTheVolumeOfASoftBallOnImpact) {
  // The same soft ball dropped at 4 m/s onto the ground, with and without gas.
  double lowest[2];
  for (int withGas = 0; withGas < 2; ++withGas) {
    Model model = gasBall(3, withGas ? 0.02 : 0.0, 0.0, 0.05, {0, -9.81, 0});
    for (Strut& s : model.struts) s.stiffness = stiffnessFromPeriod(0.5 * (model.mass[s.i] + model.mass[s.j]), 0.01);
    for (Vec3& p : model.restPosition) p.y += 1.05;
    for (Vec3& v : model.initialVelocity) v = {0, -4.0, 0};
    model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, {}});
    World world(std::move(model), Integrator::SymplecticEuler, 2e-4);
    Monitor monitor(world);
    lowest[withGas] = 1.0;
    for (int s = 0; s < 3000; ++s) {
      world.step();
      const auto failure = monitor.check(world);
      ASSERT_FALSE(failure) << failure->message;
      lowest[withGas] = std::fmin(lowest[withGas], measureBody(world, 0).volume / world.model().bodies[0].restVolume);
    }
  }
  EXPECT_LT(lowest[0], 0.85);
  EXPECT_GT(lowest[1], 0.97);
}

TEST(Gas, BackwardEulerKeepsTheVolumeAtLargeSteps) {
  // Squashed by a third and let go at 1/60 s (the gas's period is 10 ms): stable, and the ball
  // returns to its volume.
  Model model = gasBall(3, 0.01, 0.0, 0.05);
  for (Strut& s : model.struts) {
    s.stiffness = stiffnessFromPeriod(0.5 * (model.mass[s.i] + model.mass[s.j]), 0.01);
    s.damping = dampingFromDecay(0.5 * (model.mass[s.i] + model.mass[s.j]), 0.1);
  }
  std::vector<Vec3> start = model.restPosition;
  for (Vec3& p : start) p.y *= 0.67;
  World world(std::move(model), Integrator::BackwardEuler, 1.0 / 60);
  world.setState(start, std::vector<Vec3>(start.size()));
  Monitor monitor(world);
  for (int s = 0; s < 60; ++s) {
    world.step();
    const auto failure = monitor.check(world);
    ASSERT_FALSE(failure) << failure->message;
  }
  EXPECT_NEAR(measureBody(world, 0).volume / world.model().bodies[0].restVolume, 1.0, 0.01);
}

TEST(Gas, NeedsAClosedMeshThatEnclosesAVolume) {
  BodyDesc desc;
  desc.name = "leaky";
  desc.mesh = makeIcosphere(1.0, 1);
  desc.volumePeriod = 0.05;
  const Triangle removed = desc.mesh.triangles.back();
  desc.mesh.triangles.pop_back();
  Model model;
  try {
    addBody(model, desc);
    FAIL() << "no error for an open mesh";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("body 'leaky'"), std::string::npos) << message;
    EXPECT_NE(message.find("closed mesh"), std::string::npos) << message;
    // The edge it names is one of the removed triangle's.
    bool named = false;
    for (int k = 0; k < 3; ++k) {
      const std::string a = std::to_string(removed[static_cast<std::size_t>(k)]),
                        b = std::to_string(removed[static_cast<std::size_t>((k + 1) % 3)]);
      named = named || message.find("(" + a + ", " + b + ")") != std::string::npos ||
              message.find("(" + b + ", " + a + ")") != std::string::npos;
    }
    EXPECT_TRUE(named) << message;
  }
  // Faces turned inward: a negative volume.
  desc.mesh = makeIcosphere(1.0, 1);
  for (Triangle& t : desc.mesh.triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(addBody(model, desc), Error);
}

}  // namespace
}  // namespace springy

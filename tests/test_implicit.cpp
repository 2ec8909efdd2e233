// The backward Euler integrator: analytic Jacobians against finite differences, the step
// against the closed-form backward Euler map, pins, energy decay and stiff stability.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>

#include "fixtures.h"
#include "sim/diagnostics.h"
#include "sim/hinge.h"
#include "sim/implicit.h"
#include "sim/monitor.h"
#include "sim/shapes.h"
#include "sim/strut.h"

namespace springy {
namespace {

// A deterministic pseudo-random perturbation in [-1, 1].
double wobble(int i) { return std::sin(12.9898 * (i + 1) + 78.233) ; }

Vec3 perturb(int i) { return {wobble(3 * i), wobble(3 * i + 1), wobble(3 * i + 2)}; }

// Forces of one element on its vertices (all others zero), as a function of (x, v).
using ForceFn = std::function<void(const Vec3* x, const Vec3* v, Vec3* f)>;

// Central differences of f with respect to x (or v) of the listed vertices.
Eigen::MatrixXd finiteDifference(const ForceFn& force, std::vector<Vec3> x, std::vector<Vec3> v,
                                 const std::vector<uint32_t>& vertices, bool wrtVelocity, double eps) {
  const auto n = static_cast<Eigen::Index>(3 * vertices.size());
  Eigen::MatrixXd J(n, n);
  std::vector<Vec3> fp(x.size()), fm(x.size());
  for (std::size_t b = 0; b < vertices.size(); ++b) {
    for (int c = 0; c < 3; ++c) {
      std::vector<Vec3>& y = wrtVelocity ? v : x;
      const double saved = y[vertices[b]][c];
      y[vertices[b]][c] = saved + eps;
      std::fill(fp.begin(), fp.end(), Vec3{});
      force(x.data(), v.data(), fp.data());
      y[vertices[b]][c] = saved - eps;
      std::fill(fm.begin(), fm.end(), Vec3{});
      force(x.data(), v.data(), fm.data());
      y[vertices[b]][c] = saved;
      for (std::size_t a = 0; a < vertices.size(); ++a) {
        for (int r = 0; r < 3; ++r) {
          J(static_cast<Eigen::Index>(3 * a) + r, static_cast<Eigen::Index>(3 * b) + c) =
              (fp[vertices[a]][r] - fm[vertices[a]][r]) / (2 * eps);
        }
      }
    }
  }
  return J;
}

double relativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }

TEST(StrutJacobian, MatchesFiniteDifferencesOfTheForce) {
  const Strut st{0, 1, 1.3, 250.0, 3.5};
  for (int trial = 0; trial < 4; ++trial) {
    // Stretched and compressed, in general directions, with relative velocity.
    std::vector<Vec3> x = {perturb(trial) * 0.3, Vec3{1.0 + 0.4 * trial - 0.5, 0.2, -0.3} + perturb(trial + 7) * 0.2};
    std::vector<Vec3> v = {perturb(trial + 11), perturb(trial + 13)};
    Eigen::Matrix3d kx, kv;
    ASSERT_TRUE(strutJacobian(st, x.data(), v.data(), kx, kv, false));
    Eigen::MatrixXd J(6, 6), Jv(6, 6);
    J << -kx, kx, kx, -kx;
    Jv << -kv, kv, kv, -kv;
    const ForceFn f = [&](const Vec3* xx, const Vec3* vv, Vec3* ff) {
      applyStruts(&st, Elements::range(0, 1), xx, vv, ff);
    };
    EXPECT_LT(relativeError(J, finiteDifference(f, x, v, {0, 1}, false, 1e-6)), 1e-7) << "trial " << trial;
    EXPECT_LT(relativeError(Jv, finiteDifference(f, x, v, {0, 1}, true, 1e-6)), 1e-7) << "trial " << trial;
    // The definite part is symmetric positive semidefinite.
    ASSERT_TRUE(strutJacobian(st, x.data(), v.data(), kx, kv, true));
    EXPECT_LT((kx - kx.transpose()).norm(), 1e-12 * kx.norm());
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(kx).eigenvalues().minCoeff(), -1e-12 * kx.norm());
  }
}

class HingeShapes : public ::testing::TestWithParam<double> {};

TEST_P(HingeShapes, DihedralHessianMatchesFiniteDifferencesOfTheGradient) {
  std::vector<Vec3> x = test::hingePositions(GetParam());
  for (int i = 0; i < 4; ++i) x[static_cast<std::size_t>(i)] += perturb(i) * 0.05;
  Matrix12 H;
  ASSERT_TRUE(dihedralHessian(x[0], x[1], x[2], x[3], H));
  // theta's gradient is the force of a hinge with k = -1 about theta0 = theta - 1 ... more
  // simply: the force of a unit-stiffness hinge is -(theta - theta0) g, so use the gradient.
  Matrix12 fd;
  const double eps = 1e-6;
  for (int b = 0; b < 12; ++b) {
    std::vector<Vec3> xp = x, xm = x;
    xp[static_cast<std::size_t>(b / 3)][b % 3] += eps;
    xm[static_cast<std::size_t>(b / 3)][b % 3] -= eps;
    HingeGeometry gp, gm;
    ASSERT_TRUE(hingeGeometry(xp[0], xp[1], xp[2], xp[3], gp));
    ASSERT_TRUE(hingeGeometry(xm[0], xm[1], xm[2], xm[3], gm));
    for (int a = 0; a < 12; ++a) fd(a, b) = (gp.grad[a / 3][a % 3] - gm.grad[a / 3][a % 3]) / (2 * eps);
  }
  EXPECT_LT(relativeError(H, fd), 1e-7);
  EXPECT_LT((H - H.transpose()).norm(), 1e-9 * H.norm());  // a Hessian is symmetric
}

TEST_P(HingeShapes, HingeJacobianMatchesFiniteDifferencesOfTheForce) {
  const double rest = GetParam();
  const Hinge hg{{0, 1, 2, 3}, rest, 7.0, 0.8};
  std::vector<Vec3> x = test::hingePositions(rest + 0.4);  // bent away from rest
  std::vector<Vec3> v(4);
  for (int i = 0; i < 4; ++i) {
    x[static_cast<std::size_t>(i)] += perturb(i + 20) * 0.05;
    v[static_cast<std::size_t>(i)] = perturb(i + 40);
  }
  Matrix12 jx, jv;
  ASSERT_TRUE(hingeJacobian(hg, x.data(), v.data(), jx, jv, false));
  const ForceFn f = [&](const Vec3* xx, const Vec3* vv, Vec3* ff) { applyHingesDerivingTerms(&hg, 0, 1, xx, vv, ff); };
  EXPECT_LT(relativeError(jx, finiteDifference(f, x, v, {0, 1, 2, 3}, false, 1e-6)), 1e-6);
  EXPECT_LT(relativeError(jv, finiteDifference(f, x, v, {0, 1, 2, 3}, true, 1e-6)), 1e-7);
}

// Flat, convex, concave and folded close to +-pi (where the angle wraps).
INSTANTIATE_TEST_SUITE_P(Angles, HingeShapes, ::testing::Values(0.0, 0.7, -1.1, 2.6, -2.6));

TEST(HingeJacobian, StaysFiniteInACrushedFace) {
  const Hinge hg{{0, 1, 2, 3}, 0.3, 7.0, 0.8, {0.2, 0.2}};
  std::vector<Vec3> x = test::hingePositions(0.3);
  x[2] = {0.4, 1e-7, 1e-9};  // wing vertex almost on the hinge line
  std::vector<Vec3> v = {perturb(1), perturb(2), perturb(3), perturb(4)};
  Matrix12 jx, jv;
  ASSERT_TRUE(hingeJacobian(hg, x.data(), v.data(), jx, jv, true));
  EXPECT_TRUE(jx.allFinite());
  EXPECT_TRUE(jv.allFinite());
}

TEST(ImplicitSolver, GlobalAssemblyMatchesFiniteDifferencesOfAllForces) {
  // A small closed body with struts, hinges and drag, deformed and moving: the assembled
  // sparse K and D are the derivatives of World::computeForces.
  Model model;
  model.drag = 0.3;
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = makeIcosphere(1.0, 1);
  addBody(model, desc);
  World world(model, Integrator::BackwardEuler, 0.01);
  std::vector<Vec3> x = world.positions(), v(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] += perturb(static_cast<int>(i)) * 0.05;
    v[i] = perturb(static_cast<int>(i) + 100);
  }
  ImplicitSolver solver(world.model());
  solver.assemble(world.model(), x.data(), v.data(), false);
  const ForceFn f = [&](const Vec3* xx, const Vec3* vv, Vec3* ff) { world.computeForces(xx, vv, 0.0, ff); };
  std::vector<uint32_t> all(x.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  const Eigen::MatrixXd K = Eigen::MatrixXd(solver.stiffness()), D = Eigen::MatrixXd(solver.dampingMatrix());
  EXPECT_LT(relativeError(K, finiteDifference(f, x, v, all, false, 1e-6)), 1e-6);
  EXPECT_LT(relativeError(D, finiteDifference(f, x, v, all, true, 1e-6)), 1e-7);
}

TEST(BackwardEuler, OneStepEqualsTheClosedFormBackwardEulerMap) {
  test::expectTheClosedFormBackwardEulerMap(Integrator::BackwardEuler, 0.05, 1, 1e-9, 1e-12);
}

TEST(BackwardEuler, PinnedVertexStaysPutAndTheHangingMassSettles) {
  Model model = test::strutModel(1.0, 2.0, 1.0, 100.0, 5.0, true);
  model.gravity = {0, -9.81, 0};
  World world(std::move(model), Integrator::BackwardEuler, 1.0 / 60);
  world.setState({{0, 0, 0}, {0, -1, 0}}, {{}, {}});  // hanging straight down from the pin
  for (int s = 0; s < 600; ++s) world.step();
  EXPECT_EQ(world.positions()[0], (Vec3{0, 0, 0}));
  // Equilibrium: the strut stretches by m g / k straight down from the pin.
  EXPECT_NEAR(length(world.positions()[1]), 1.0 + 2.0 * 9.81 / 100.0, 1e-3);
  EXPECT_LT(length(world.velocities()[1]), 1e-3);
}

TEST(BackwardEuler, UndampedEnergyNeverRisesEvenAtHugeSteps) {
  // Backward Euler is A-stable: the energy of an undamped oscillator decays at any step, even
  // ten times its period.
  for (double h : {0.001, 0.01, 0.1, 1.0}) {
    World world(test::hingeModel(0.4, 5.0, 0.0, true, 300.0, 0.0), Integrator::BackwardEuler, h);
    std::vector<Vec3> x = test::hingePositions(1.4);
    world.setState(x, std::vector<Vec3>(4));
    double previous = measureBody(world, 0).total();
    for (int s = 0; s < 50; ++s) {
      world.step();
      const double e = measureBody(world, 0).total();
      ASSERT_LE(e, previous * (1 + 1e-9) + 1e-12) << "dt " << h << " step " << s;
      previous = e;
    }
  }
}

TEST(BackwardEuler, StiffBallStaysStableAtOneSixtiethOfASecond) {
  // P = P_theta = 1 ms: explicit integrators need dt below about 0.1 ms here.
  Model model;
  BodyDesc desc;
  desc.name = "stiff";
  desc.mesh = makeIcosphere(1.0, 2);
  desc.strutPeriod = 0.001;
  desc.hingePeriod = 0.001;
  desc.strutDecay = 1.0;
  desc.hingeDecay = 1.0;
  desc.velocity = {0, 0, 2.0};
  addBody(model, desc);
  for (Vec3& p : model.restPosition) p.y *= 0.7;  // start squashed
  World world(std::move(model), Integrator::BackwardEuler, 1.0 / 60);
  Monitor monitor(world);
  for (int s = 0; s < 60; ++s) {
    world.step();
    const auto failure = monitor.check(world);
    ASSERT_FALSE(failure) << failure->message;
  }
  // It has recovered its rest volume and still moves with its initial momentum.
  const BodyMeasures m = measureBody(world, 0);
  EXPECT_NEAR(m.volume / world.model().bodies[0].restVolume, 1.0, 0.05);
  EXPECT_NEAR(m.momentum.z, 2.0 * 1.0, 1e-6);
}

}  // namespace
}  // namespace springy

// Small hand-built worlds for the physics tests.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/cases.h"
#include "sim/model.h"
#include "sim/world.h"

namespace springy::test {

// The hand-built models live in sim/cases.h, shared with the studies and the benchmarks.
using springy::hingeModel;
using springy::hingePositions;
using springy::strutModel;
using springy::vertexModel;

// Two masses (1.5 and 0.5 kg) on a damped strut along x (l0 1 m, k 400 N/m, d 3 N s/m): the
// relative coordinate is a linear oscillator mu y'' = -k (y - l0) - d y', whose backward Euler
// step is the solution of a 2x2 system. Five steps of h of an implicit integrator (at
// `iterations` sweeps, for vbd) against that map, to `tolerance` [m] (velocities to 10 times it),
// and the momentum, which the step keeps, to `momentumTolerance` [kg m/s].
inline void expectTheClosedFormBackwardEulerMap(Integrator integrator, double h, int iterations, double tolerance,
                                                double momentumTolerance) {
  const double m0 = 1.5, m1 = 0.5, l0 = 1.0, k = 400.0, d = 3.0;
  World world(strutModel(m0, m1, l0, k, d, false), integrator, h);
  world.setIterations(iterations);
  world.setState({{0, 0, 0}, {1.2, 0, 0}}, {{0.1, 0, 0}, {-0.7, 0, 0}});
  const double mu = m0 * m1 / (m0 + m1);
  double y = 0.2, w = -0.8;  // y = l - l0, w = y'
  for (int s = 0; s < 5; ++s) {
    // (1 + h d/mu + h^2 k/mu) w1 = w - h k/mu y ;  y1 = y + h w1
    const double w1 = (w - h * k / mu * y) / (1.0 + h * d / mu + h * h * k / mu);
    y += h * w1;
    w = w1;
    world.step();
  }
  const auto& x = world.positions();
  EXPECT_NEAR(x[1].x - x[0].x - l0, y, tolerance);
  EXPECT_NEAR(world.velocities()[1].x - world.velocities()[0].x, w, 10 * tolerance);
  EXPECT_NEAR(m0 * world.velocities()[0].x + m1 * world.velocities()[1].x, m0 * 0.1 + m1 * -0.7, momentumTolerance);
}

}  // namespace springy::test

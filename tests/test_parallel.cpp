// Threads: every thread count gives bit-identical results (sim/parallel.h), and the pool and
// the split behave as documented.
#include <gtest/gtest.h>
#include <sched.h>

#include <atomic>
#include <cstdlib>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/parallel.h"
#include "sim/strut.h"
#include "sim/world.h"

namespace springy {
namespace {

// Every force stage and both collider kinds: three bodies (one pinned, one holding gas, one of
// the body material with its deformation damping) with drag and gusting wind, a ground plane
// and a tilted plate they fall onto.
const char* kAllStages = R"(
[scene]
dt = 0.001
[environment]
drag = 0.2
[environment.wind]
velocity = [3.0, 0.0, 1.0]
gust_strength = 0.5
pressure = 0.8
seed = 11
[[body]]
name = "ball"
shape = "icosphere"
subdivisions = 3
radius = 1.0
position = [0.0, 1.6, 0.0]
velocity = [0.5, -2.0, 0.0]
strut_period = 0.05
hinge_period = 0.2
volume_period = 0.03
[[body]]
name = "hanging"
shape = "octahedron_sphere"
subdivisions = 6
radius = 0.6
position = [3.0, 2.0, 0.0]
pin = ["top"]
strut_period = 0.07
[[body]]
name = "damped by its deformation"
shape = "icosphere"
subdivisions = 1
radius = 0.4
position = [-2.0, 1.0, 0.0]
velocity = [0.0, 0.0, 1.0]
angular_velocity = [0.0, 3.0, 0.0]
material = "body"
stretch_period = 0.5
bend_period = 2.0
deformation_decay = 0.005
[[plane]]
[[triangles]]
vertices = [[-2.0, 0.2, -2.0], [2.0, 0.6, -2.0], [2.0, 0.6, 2.0], [-2.0, 0.2, 2.0]]
indices = [[0, 1, 2], [0, 2, 3]]
)";

World makeWorld(Integrator integrator, unsigned threads) {
  const SceneDesc scene = parseScene(kAllStages, "/virtual/all_stages.toml");
  World world(buildModel(scene), integrator, stepSize(scene));
  world.setThreads(threads, 0);  // threads even for this small model
  return world;
}

class ThreadCounts : public ::testing::TestWithParam<Integrator> {};

TEST_P(ThreadCounts, GiveBitIdenticalStates) {
  // 0.4 s: the ball hits the plate and the plane; the implicit integrator (slower per step)
  // runs 0.15 s, which includes the first contact.
  const int steps = isImplicit(GetParam()) ? 150 : 400;
  World reference = makeWorld(GetParam(), 1);
  ASSERT_EQ(reference.threads(), 1u);
  for (int s = 0; s < steps; ++s) reference.step();
  const uint64_t expected = stateHash(reference);
  // The run must have done something: contact and motion.
  ASSERT_GT(measureBody(reference, 0).rmsSpeed, 0.1);
  for (unsigned threads : {2u, 3u, 4u, 7u}) {
    World world = makeWorld(GetParam(), threads);
    ASSERT_EQ(world.threads(), threads);
    for (int s = 0; s < steps; ++s) world.step();
    EXPECT_EQ(stateHash(world), expected) << threads << " threads, " << integratorName(GetParam());
  }
}

INSTANTIATE_TEST_SUITE_P(Integrators, ThreadCounts,
                         ::testing::Values(Integrator::ExplicitEuler, Integrator::SymplecticEuler,
                                           Integrator::VelocityVerlet, Integrator::Leapfrog, Integrator::RK4,
                                           Integrator::BackwardEuler, Integrator::Vbd),
                         [](const auto& param) { return std::string(integratorName(param.param)); });

TEST(ThreadSplit, ForcesEqualTheOneThreadedSumExactly) {
  World one = makeWorld(Integrator::SymplecticEuler, 1);
  World two = makeWorld(Integrator::SymplecticEuler, 2);
  for (int s = 0; s < 50; ++s) one.step();
  std::vector<Vec3> f1(one.model().vertexCount()), f2(f1.size());
  one.computeForces(one.positions().data(), one.velocities().data(), one.time(), f1.data());
  two.computeForces(one.positions().data(), one.velocities().data(), one.time(), f2.data());
  for (std::size_t i = 0; i < f1.size(); ++i) ASSERT_EQ(f1[i], f2[i]) << "vertex " << i;
}

TEST(ThreadSplit, MeasurementsAreTheSameOnEveryThreadCountAndCoverTheWholeBody) {
  // measureBody splits a body into regions of 512 vertices on the world's threads (the ball
  // has two) and adds the regions' sums in order: the same bits on every thread count, and
  // the same totals as plain loops over the whole body.
  World one = makeWorld(Integrator::SymplecticEuler, 1);
  for (int s = 0; s < 200; ++s) one.step();
  const Model& model = one.model();
  const Vec3* x = one.positions().data();
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    const BodyInfo& info = model.bodies[b];
    const BodyMeasures m = measureBody(one, b);
    EXPECT_EQ(m.volume, enclosedVolume(model, b, x)) << info.name;
    const StrutMeasures struts = measureStruts(model.struts.data(), info.firstStrut, info.firstStrut + info.strutCount, x);
    EXPECT_EQ(m.maxStrain, struts.maxStrain) << info.name;
    const double elastic = struts.energy + hingeEnergy(model.hinges.data(), info.firstHinge,
                                                       info.firstHinge + info.hingeCount, x) +
                           gasEnergy(info, m.volume);
    EXPECT_NEAR(m.elastic, elastic, 1e-12 * elastic) << info.name;
    double kinetic = 0.0;
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      kinetic += 0.5 * model.mass[i] * lengthSquared(one.velocities()[i]);
    }
    EXPECT_NEAR(m.kinetic, kinetic, 1e-12 * kinetic) << info.name;
    ASSERT_GT(kinetic, 0.0);
  }
  for (unsigned threads : {2u, 3u, 7u}) {
    World world = makeWorld(Integrator::SymplecticEuler, threads);
    for (int s = 0; s < 200; ++s) world.step();
    ASSERT_EQ(stateHash(world), stateHash(one));
    for (uint32_t b = 0; b < model.bodies.size(); ++b) {
      const BodyMeasures expected = measureBody(one, b), m = measureBody(world, b);
      EXPECT_EQ(m.centroid, expected.centroid) << threads << " threads";
      EXPECT_EQ(m.momentum, expected.momentum) << threads << " threads";
      EXPECT_EQ(m.angularMomentum, expected.angularMomentum) << threads << " threads";
      EXPECT_EQ(m.kinetic, expected.kinetic) << threads << " threads";
      EXPECT_EQ(m.gravitational, expected.gravitational) << threads << " threads";
      EXPECT_EQ(m.elastic, expected.elastic) << threads << " threads";
      EXPECT_EQ(m.volume, expected.volume) << threads << " threads";
      EXPECT_EQ(m.size, expected.size) << threads << " threads";
      EXPECT_EQ(m.maxStrain, expected.maxStrain) << threads << " threads";
      EXPECT_EQ(m.penetration, expected.penetration) << threads << " threads";
      EXPECT_EQ(m.rmsSpeed, expected.rmsSpeed) << threads << " threads";
    }
  }
}

TEST(ThreadSplit, SpatialRangesKeepTheDuplicatedWorkSmall) {
  // Elements across the boundary between two threads' vertex ranges are evaluated twice; for a
  // compact split that is a thin band (for this 2-body scene well under 10% of elements).
  const World world = makeWorld(Integrator::SymplecticEuler, 2);
  EXPECT_GT(world.redundancy(), 1.0);
  EXPECT_LT(world.redundancy(), 1.1);
}

TEST(ThreadSplit, SmallModelsStayOnOneThread) {
  const SceneDesc scene = parseScene(kAllStages, "/virtual/all_stages.toml");
  World world(buildModel(scene), Integrator::RK4, 1e-3);
  world.setThreads(8);  // 642 + 146 vertices: under kMinVerticesPerThread (1000) for two threads
  EXPECT_EQ(world.threads(), 1u);
}

TEST(ThreadPool, RunsEveryThreadIndexOncePerJob) {
  ThreadPool pool(3);
  std::vector<std::atomic<int>> calls(3);
  for (int job = 0; job < 1000; ++job) {
    pool.run([&](unsigned t) { calls[t].fetch_add(1); });
  }
  for (const auto& c : calls) EXPECT_EQ(c.load(), 1000);
  std::vector<int> covered(1001, 0);
  pool.forRange(covered.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) covered[i]++;
  });
  for (int c : covered) ASSERT_EQ(c, 1);
}

// On one core (the others busy, as on a loaded machine) the workers seldom run when a job
// starts: the calling thread takes their shares over instead of waiting for them to be scheduled.
// Every share still runs exactly once per job.
TEST(ThreadPool, TheCallerTakesOverSharesNoWorkerStarted) {
  cpu_set_t before, one;
  ASSERT_EQ(sched_getaffinity(0, sizeof(before), &before), 0);
  CPU_ZERO(&one);
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(c, &before)) {
      CPU_SET(c, &one);
      break;
    }
  }
  ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);  // the pool's threads inherit it
  {
    ThreadPool pool(4);
    std::vector<std::atomic<int>> calls(4);
    int jobs = 0;
    for (; jobs < 20000 && (jobs < 1000 || pool.sharesTakenOver() == 0); ++jobs) {
      pool.run([&](unsigned t) { calls[t].fetch_add(1); });
    }
    for (const auto& c : calls) EXPECT_EQ(c.load(), jobs);
    EXPECT_GT(pool.sharesTakenOver(), 0u) << "after " << jobs << " jobs";
  }
  ASSERT_EQ(sched_setaffinity(0, sizeof(before), &before), 0);
}

// The pool's rule for running alone: a window in which waiting for the workers cost more than
// the other shares' work done here would have sends the caller alone for a window, then two, four
// ... (up to the cap); a window the workers win resets it.
TEST(ContentionScore, RunsAloneAfterALosingWindowForLongerEachTime) {
  ContentionScore score(2);
  const auto window = [&](int64_t own, int64_t wait) {
    uint64_t solo = 0;
    for (unsigned j = 0; j < ContentionScore::kWindow; ++j) {
      const uint64_t s = score.record(own, wait);
      if (j + 1 < ContentionScore::kWindow) {
        EXPECT_EQ(s, 0u) << "decided before the window ended";
      }
      solo = s;
    }
    return solo;
  };
  EXPECT_EQ(window(1000, 900), 0u);  // waiting less than the other share would take: keep them
  EXPECT_EQ(window(1000, 1100), ContentionScore::kWindow);
  EXPECT_EQ(window(1000, 5000), 2u * ContentionScore::kWindow);
  EXPECT_EQ(window(1000, 5000), 4u * ContentionScore::kWindow);
  for (int k = 0; k < 20; ++k) window(1000, 5000);
  EXPECT_EQ(window(1000, 5000), uint64_t{ContentionScore::kMaxSoloWindows} * ContentionScore::kWindow);
  EXPECT_EQ(window(1000, 100), 0u);  // the workers won: back to one window
  EXPECT_EQ(window(1000, 5000), ContentionScore::kWindow);
  // Four threads: the caller would run three other shares, so waiting up to three times its own
  // time still pays.
  ContentionScore four(4);
  uint64_t solo = 0;
  for (unsigned j = 0; j < ContentionScore::kWindow; ++j) solo = four.record(1000, 2900);
  EXPECT_EQ(solo, 0u);
}

TEST(ThreadPool, BadThreadCountInTheEnvironmentIsAnError) {
  ::setenv("SPRINGY_THREADS", "two", 1);
  try {
    defaultThreadCount();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("SPRINGY_THREADS=two"), std::string::npos) << e.what();
  }
  ::setenv("SPRINGY_THREADS", "3", 1);
  EXPECT_EQ(defaultThreadCount(), 3u);
  ::unsetenv("SPRINGY_THREADS");
  EXPECT_GE(defaultThreadCount(), 1u);
}

}  // namespace
}  // namespace springy

// Google Benchmark binaries for the simulation: the force kernels per element, a whole force
// evaluation, whole steps per integrator, the scaling over mesh size and thread count, and the
// cost of stages a scene does not use. Run: build/bench/bench_sim (see docs/benchmarks.md).
//
// Counters: ns_per_strut / ns_per_hinge are per element per force evaluation; ns_per_vertex
// is per vertex per step.
#include <benchmark/benchmark.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "sim/contact.h"
#include "sim/diagnostics.h"
#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/model.h"
#include "sim/shapes.h"
#include "sim/strut.h"
#include "sim/world.h"

namespace springy {
namespace {

// A ball of the given icosphere level (162 vertices at level 2 ... 163842 at level 7), 1 m
// across, 1 kg, with the drop test's stiffness, its lowest point 1.5 m above a ground plane.
BodyDesc ballDesc(int level) {
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = makeIcosphere(0.5, level);
  for (Vec3& p : desc.mesh.positions) p.y += 2.0;
  desc.mass = 1.0;
  desc.strutPeriod = 0.05;
  desc.strutDecay = 0.1;
  desc.hingePeriod = 0.2;
  desc.hingeDecay = 0.5;
  return desc;
}
Model ballModel(int level, bool withPlane = true) {
  Model model;
  addBody(model, ballDesc(level));
  if (withPlane) model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, 0.5, 0.3});
  return model;
}

// An n x n grid of vertices 1 m across in the x-z plane at height 1 (an open mesh: struts on
// every edge and diagonal, hinges on interior edges), pinned at two corners.
Model clothModel(int n) {
  BodyDesc desc;
  desc.name = "cloth";
  const double h = 1.0 / (n - 1);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) desc.mesh.positions.push_back({c * h, 1.0, r * h});
  }
  for (int r = 0; r + 1 < n; ++r) {
    for (int c = 0; c + 1 < n; ++c) {
      const auto v = [n](int rr, int cc) { return static_cast<uint32_t>(rr * n + cc); };
      desc.mesh.triangles.push_back({v(r, c), v(r + 1, c), v(r, c + 1)});
      desc.mesh.triangles.push_back({v(r, c + 1), v(r + 1, c), v(r + 1, c + 1)});
    }
  }
  desc.mass = 0.5;
  desc.strutPeriod = 0.05;
  desc.strutDecay = 0.1;
  desc.hingePeriod = 0.5;
  desc.hingeDecay = 1.0;
  desc.pinned = {0, static_cast<uint32_t>(n - 1)};
  Model model;
  addBody(model, desc);
  return model;
}

// A deformed, moving state (not the rest state, so every kernel does its full work): every
// vertex moved by up to 5% of the mean strut length, speeds up to 0.1 m/s.
void perturbedState(const Model& model, std::vector<Vec3>& x, std::vector<Vec3>& v) {
  double meanLength = 0.0;
  for (const Strut& s : model.struts) meanLength += s.restLength;
  meanLength /= static_cast<double>(model.struts.size());
  const double a = 0.05 * meanLength;
  x = model.restPosition;
  v.assign(x.size(), Vec3{});
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double s = static_cast<double>(i);
    x[i] += Vec3{a * std::sin(1.3 * s), a * std::cos(0.7 * s), a * std::sin(2.1 * s)};
    v[i] = Vec3{0.1 * std::cos(0.9 * s), 0.1 * std::sin(1.7 * s), 0.1 * std::cos(0.3 * s)};
  }
}

// Reports `count` items per iteration as nanoseconds per item (wall time).
void nsPer(benchmark::State& state, const char* name, double count) {
  state.counters[name] = benchmark::Counter(count * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                                              benchmark::Counter::kInvert);
}

// --- force kernels, one core, per element

void BM_StrutKernel(benchmark::State& state) {
  const Model model = ballModel(static_cast<int>(state.range(0)), false);
  std::vector<Vec3> x, v, f(model.vertexCount());
  perturbedState(model, x, v);
  for (auto _ : state) {
    applyStruts(model.struts.data(), Elements::range(0, model.struts.size()), x.data(), v.data(), f.data());
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  nsPer(state, "ns_per_strut", static_cast<double>(model.struts.size()));
}
BENCHMARK(BM_StrutKernel)->DenseRange(2, 6)->UseRealTime();

// The hinges of a ball, all in one call (four-lane packets) or one hinge per call (the
// one-hinge kernel): the packets' gain, measured in the same run.
void hingeKernel(benchmark::State& state, bool oneAtATime) {
  const Model model = ballModel(static_cast<int>(state.range(0)), false);
  std::vector<HingeTerms> terms;
  for (const Hinge& h : model.hinges) terms.push_back(hingeTerms(h));
  std::vector<Vec3> x, v, f(model.vertexCount());
  perturbedState(model, x, v);
  const std::size_t n = model.hinges.size(), chunk = oneAtATime ? 1 : n;
  for (auto _ : state) {
    for (std::size_t k = 0; k < n; k += chunk) {
      applyHinges(model.hinges.data(), terms.data(), Elements::range(k, k + chunk), x.data(), v.data(), f.data());
    }
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  nsPer(state, "ns_per_hinge", static_cast<double>(n));
}
void BM_HingeKernel(benchmark::State& state) { hingeKernel(state, false); }
void BM_HingeKernelOneAtATime(benchmark::State& state) { hingeKernel(state, true); }
BENCHMARK(BM_HingeKernel)->DenseRange(2, 6)->UseRealTime();
BENCHMARK(BM_HingeKernelOneAtATime)->DenseRange(2, 6)->UseRealTime();

// --- a whole force evaluation (every stage of the ball: gravity, struts, hinges)

void BM_Forces(benchmark::State& state) {
  const Model model = ballModel(static_cast<int>(state.range(0)), false);
  const World world(model, Integrator::SymplecticEuler, 1e-3);
  std::vector<Vec3> x, v, f(model.vertexCount());
  perturbedState(model, x, v);
  for (auto _ : state) {
    world.computeForces(x.data(), v.data(), 0.0, f.data());
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_Forces)->DenseRange(2, 6)->UseRealTime();

// --- contact between bodies (sim/contact.h): a layer of touching balls on the ground

// `count` balls of the body material (icosphere `level`, radius 0.25 m, 0.5 kg) side by side in a
// square grid on the ground, each a quarter of its contact thickness from its neighbours (so
// every neighbour pair is in contact, as in a resting pile), and one free-fall step of
// dt = 2e-4 s from rest: x1 = x0 + g dt^2, v1 = g dt.
struct ContactLayer {
  Model model;
  std::vector<Vec3> x0, x1, v1;
  double dt = 2e-4;
};
ContactLayer contactLayer(int level, int count) {
  ContactLayer layer;
  layer.model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, 0.0, 0.5});
  const TriMesh sphere = makeIcosphere(0.25, level);
  double edges = 0.0;
  for (const Triangle& t : sphere.triangles) edges += length(sphere.positions[t[1]] - sphere.positions[t[0]]);
  const double gap = 0.25 * kDefaultThicknessFactor * edges / static_cast<double>(sphere.triangles.size());
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
  for (int k = 0; k < count; ++k) {
    BodyDesc desc;
    desc.name = "ball " + std::to_string(k);
    desc.mesh = sphere;
    const Vec3 at{(k % side) * (0.5 + gap), 0.25 + gap, (k / side) * (0.5 + gap)};
    for (Vec3& p : desc.mesh.positions) p += at;
    desc.mass = 0.5;
    desc.material = MaterialModel::Body;
    addBody(layer.model, desc);
  }
  layer.x0 = layer.model.restPosition;
  layer.x1 = layer.x0;
  layer.v1.assign(layer.x0.size(), Vec3{0.0, -9.81 * layer.dt, 0.0});
  for (Vec3& p : layer.x1) p.y -= 9.81 * layer.dt * layer.dt;
  return layer;
}

// The contact stage's search and response for one step (state.range(0): the icosphere level,
// range(1): the number of balls); the copy of the step's end state each iteration is included.
void BM_ContactStage(benchmark::State& state) {
  const ContactLayer layer = contactLayer(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  BodyContacts contacts(layer.model);
  std::vector<Vec3> x1, v1;
  uint64_t found = 0;
  for (auto _ : state) {
    x1 = layer.x1, v1 = layer.v1;
    contacts.resolve(layer.x0, x1, v1, layer.dt);
    found = contacts.lastStep().contacts;
    benchmark::DoNotOptimize(x1.data());
  }
  state.counters["contacts"] = static_cast<double>(found);
  nsPer(state, "ns_per_vertex", static_cast<double>(layer.model.vertexCount()));
}
// One force evaluation of the same layer, for the ratio.
void BM_ContactLayerForces(benchmark::State& state) {
  const ContactLayer layer = contactLayer(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const World world(layer.model, Integrator::SymplecticEuler, layer.dt);
  std::vector<Vec3> f(layer.model.vertexCount());
  for (auto _ : state) {
    world.computeForces(layer.x1.data(), layer.v1.data(), 0.0, f.data());
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  nsPer(state, "ns_per_vertex", static_cast<double>(layer.model.vertexCount()));
}
// Linear in the number of bodies (2 to 64 balls of 162 vertices), and a pile's size: 27 balls of
// 642 vertices, 17334 vertices.
BENCHMARK(BM_ContactStage)->ArgsProduct({{2}, {2, 4, 8, 16, 32, 64}})->Args({3, 27})->UseRealTime();
BENCHMARK(BM_ContactLayerForces)->ArgsProduct({{2}, {2, 4, 8, 16, 32, 64}})->Args({3, 27})->UseRealTime();

// --- whole steps: integrator x mesh size (icosphere levels 2..7), ball resting on a plane

void BM_Step(benchmark::State& state) {
  const auto integrator = static_cast<Integrator>(state.range(0));
  const Model model = ballModel(static_cast<int>(state.range(1)));
  World world(model, integrator, 2e-4);
  for (auto _ : state) world.step();
  state.SetLabel(std::string(integratorName(integrator)));
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_Step)
    ->ArgsProduct({{static_cast<int>(Integrator::SymplecticEuler), static_cast<int>(Integrator::VelocityVerlet),
                    static_cast<int>(Integrator::Leapfrog), static_cast<int>(Integrator::RK4)},
                   {2, 4}})
    ->UseRealTime();
BENCHMARK(BM_Step)
    ->ArgsProduct({{static_cast<int>(Integrator::SymplecticEuler)}, {2, 3, 4, 5, 6, 7}})
    ->UseRealTime()
    ->Name("BM_StepScaling");

// Threads: the same step on 1 and 2 threads (results are bit-identical; tests/test_parallel).
void BM_StepThreads(benchmark::State& state) {
  const Model model = ballModel(static_cast<int>(state.range(0)));
  World world(model, Integrator::RK4, 2e-4);
  world.setThreads(static_cast<unsigned>(state.range(1)), 0);
  for (auto _ : state) world.step();
  state.counters["redundancy"] = world.redundancy();
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_StepThreads)->ArgsProduct({{2, 3, 4, 5, 6, 7}, {1, 2}})->UseRealTime();

// The time-to-solution ball of docs/bench-bullet.md (bench/drop_2562_gas.toml): 2562
// vertices, struts P 15 ms, gas P_V 10 ms, no hinges, symplectic Euler at dt 1.5 ms, dropped
// onto a plane; a cheap step, where fork-joins and traffic between the cores weigh most.
void BM_GasBallStep(benchmark::State& state) {
  Model model;
  BodyDesc desc = ballDesc(4);
  desc.strutPeriod = 0.015;
  desc.hingePeriod = 0.0;
  desc.volumePeriod = 0.01;
  addBody(model, desc);
  model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, 0.6, 0.3});
  World world(model, Integrator::SymplecticEuler, 0.0015);
  world.setThreads(static_cast<unsigned>(state.range(0)), 0);
  for (auto _ : state) world.step();
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_GasBallStep)->Arg(1)->Arg(2)->UseRealTime();

// The monitor's sample of that ball (measureBody: energies, strain, volume, bounds), which
// `springy check` takes once per output frame: at the bench scene's 120 frames/s, once every
// 4.8 steps. Taken half-way through the fall and bounce (t = 0.6 s, just after the impact).
void BM_GasBallMeasure(benchmark::State& state) {
  Model model;
  BodyDesc desc = ballDesc(4);
  desc.strutPeriod = 0.015;
  desc.hingePeriod = 0.0;
  desc.volumePeriod = 0.01;
  addBody(model, desc);
  model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, 0.6, 0.3});
  World world(model, Integrator::SymplecticEuler, 0.0015);
  world.setThreads(static_cast<unsigned>(state.range(0)), 0);
  while (world.time() < 0.6) world.step();
  double sink = 0.0;
  for (auto _ : state) {
    const BodyMeasures m = measureBody(world, 0);
    sink += m.kinetic + m.volume;
  }
  benchmark::DoNotOptimize(sink);
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_GasBallMeasure)->Arg(1)->Arg(2)->UseRealTime();

// The machine: one cache-line round trip between two threads (each waits for the other's
// write). What a fork-join and every vertex one core writes and the other reads cost; on a
// shared VM it changes with where the host places the two virtual cores.
void BM_CoreToCoreRoundTrip(benchmark::State& state) {
  alignas(64) std::atomic<uint64_t> flag{0};
  std::atomic<bool> stop{false};
  std::thread partner([&] {
    uint64_t seen = 0;
    while (!stop.load(std::memory_order_relaxed)) {
      const uint64_t now = flag.load(std::memory_order_acquire);
      if (now != seen && (now & 1u)) {
        seen = now + 1;
        flag.store(seen, std::memory_order_release);
      }
    }
  });
  uint64_t value = 0;
  for (auto _ : state) {
    flag.store(++value, std::memory_order_release);  // odd: a ping
    ++value;
    while (flag.load(std::memory_order_acquire) != value) {
    }
  }
  stop.store(true);
  partner.join();
}
BENCHMARK(BM_CoreToCoreRoundTrip)->UseRealTime();

void BM_ClothStepThreads(benchmark::State& state) {
  const Model model = clothModel(100);
  World world(model, Integrator::RK4, 2e-4);
  world.setThreads(static_cast<unsigned>(state.range(0)), 0);
  for (auto _ : state) world.step();
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_ClothStepThreads)->Arg(1)->Arg(2)->UseRealTime();

// A 100 x 100 cloth pinned at two corners (and smaller ones for the scaling).
void BM_ClothStep(benchmark::State& state) {
  const Model model = clothModel(static_cast<int>(state.range(0)));
  World world(model, Integrator::SymplecticEuler, 2e-4);
  for (auto _ : state) world.step();
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_ClothStep)->Arg(25)->Arg(50)->Arg(100)->Arg(200)->UseRealTime();

// --- "an unused feature costs nothing": the World's step for a scene with gravity, struts,
// hinges and one plane (no drag, wind or triangle colliders), against the same step written
// out by hand with only those stages, as a build without the other features would run it.

void BM_UnusedStages_World(benchmark::State& state) {
  const Model model = ballModel(static_cast<int>(state.range(0)));
  World world(model, Integrator::SymplecticEuler, 2e-4);
  for (auto _ : state) world.step();
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_UnusedStages_World)->Arg(4)->UseRealTime();

void BM_UnusedStages_HandWritten(benchmark::State& state) {
  const Model model = ballModel(static_cast<int>(state.range(0)));
  const std::size_t n = model.vertexCount();
  const double dt = 2e-4;
  std::vector<Vec3> x = model.restPosition, v = model.initialVelocity, xOld(n), f(n);
  std::vector<uint16_t> since(n, 0xFFFF);
  const int restingSteps = static_cast<int>(std::ceil(model.colliders.restingWindow / dt));
  const PlaneCollider& plane = model.colliders.planes[0];
  std::vector<HingeTerms> terms;
  for (const Hinge& h : model.hinges) terms.push_back(hingeTerms(h));
  for (auto _ : state) {
    xOld = x;
    for (std::size_t i = 0; i < n; ++i) f[i] = model.gravity * model.mass[i];
    applyStruts(model.struts.data(), Elements::range(0, model.struts.size()), x.data(), v.data(), f.data());
    applyHinges(model.hinges.data(), terms.data(), Elements::range(0, model.hinges.size()), x.data(), v.data(),
                f.data());
    for (std::size_t i = 0; i < n; ++i) {
      v[i] += f[i] * (model.invMass[i] * dt);
      x[i] += v[i] * dt;
    }
    for (std::size_t i = 0; i < n; ++i) {
      // Only the plane: what the collision pass reduces to without triangle colliders.
      const double depth = dot(x[i] - plane.point, plane.normal);
      bool hit = false;
      if (depth < 0.0) hit = model.colliders.resolve(xOld[i], x[i], v[i], since[i] <= restingSteps);
      since[i] = hit ? 0 : static_cast<uint16_t>(std::min<int>(since[i] + 1, 0xFFFF));
    }
    benchmark::DoNotOptimize(x.data());
  }
  nsPer(state, "ns_per_vertex", static_cast<double>(n));
}
BENCHMARK(BM_UnusedStages_HandWritten)->Arg(4)->UseRealTime();

}  // namespace
}  // namespace springy

BENCHMARK_MAIN();

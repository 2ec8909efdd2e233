// Google Benchmark binaries for the simulation: the force kernels per element, a whole force
// evaluation, whole steps per integrator, the scaling over mesh size and thread count, and the
// cost of stages a scene does not use. Run: build/bench/bench_sim (see docs/benchmarks.md).
//
// Counters: ns_per_strut / ns_per_hinge are per element per force evaluation; ns_per_vertex
// is per vertex per step.
#include <Eigen/Sparse>
#include <benchmark/benchmark.h>
#include <immintrin.h>

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

// An experiment for issue 19 (not springy's kernel): the strut forces in single precision,
// eight struts a packet in AVX2, with the positions and velocities stored as floats, one array
// per coordinate (as a simulator whose state were floats would keep them), the ends gathered
// (vgatherdps) and the forces added per strut end as springy's kernel adds them. What eight
// lanes instead of four could give the strut kernel at best, against BM_StrutKernel.
struct FloatStruts {
  std::vector<int32_t> i, j;
  std::vector<float> restLength, stiffness, damping;
};

FloatStruts floatStruts(const Model& model) {
  FloatStruts s;
  for (const Strut& st : model.struts) {
    s.i.push_back(static_cast<int32_t>(st.i)), s.j.push_back(static_cast<int32_t>(st.j));
    s.restLength.push_back(static_cast<float>(st.restLength)), s.stiffness.push_back(static_cast<float>(st.stiffness));
    s.damping.push_back(static_cast<float>(st.damping));
  }
  return s;
}

// Struts [r, r + 8): their forces on their first ends from the end-to-end vectors d and the
// velocity differences w (one lane a strut).
__attribute__((target("avx2,fma"))) inline void packetForce(const FloatStruts& s, std::size_t r, const __m256 d[3],
                                                            const __m256 w[3], __m256 force[3]) {
  const __m256 ll = _mm256_fmadd_ps(d[2], d[2], _mm256_fmadd_ps(d[1], d[1], _mm256_mul_ps(d[0], d[0])));
  const __m256 len = _mm256_sqrt_ps(ll);
  const __m256 inv = _mm256_div_ps(_mm256_set1_ps(1.0f), len);
  __m256 u[3];
  for (int c = 0; c < 3; ++c) u[c] = _mm256_mul_ps(d[c], inv);
  const __m256 rate = _mm256_fmadd_ps(w[2], u[2], _mm256_fmadd_ps(w[1], u[1], _mm256_mul_ps(w[0], u[0])));
  const __m256 scale =
      _mm256_fmadd_ps(_mm256_loadu_ps(&s.stiffness[r]), _mm256_sub_ps(len, _mm256_loadu_ps(&s.restLength[r])),
                      _mm256_mul_ps(_mm256_loadu_ps(&s.damping[r]), rate));
  for (int c = 0; c < 3; ++c) force[c] = _mm256_mul_ps(u[c], scale);
}

// The experiments' ball (level state.range(0)) in a perturbed state, its struts in floats; false
// (the benchmark skipped) where the machine has no AVX2 and FMA.
struct FloatCase {
  Model model;
  std::vector<Vec3> x, v;
  FloatStruts struts;
};
bool floatCase(benchmark::State& state, FloatCase& c) {
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) {
    state.SkipWithError("needs AVX2 and FMA");
    return false;
  }
  c.model = ballModel(static_cast<int>(state.range(0)), false);
  perturbedState(c.model, c.x, c.v);
  c.struts = floatStruts(c.model);
  return true;
}

__attribute__((target("avx2,fma"))) void strutsFloat8(const FloatStruts& s, const float* const x[3],
                                                      const float* const v[3], float* const f[3]) {
  const std::size_t n = s.i.size();
  alignas(32) float out[3][8];
  std::size_t r = 0;
  for (; r + 8 <= n; r += 8) {
    const __m256i I = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&s.i[r]));
    const __m256i J = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&s.j[r]));
    __m256 d[3], w[3];
    for (int c = 0; c < 3; ++c) {
      d[c] = _mm256_sub_ps(_mm256_i32gather_ps(x[c], J, 4), _mm256_i32gather_ps(x[c], I, 4));
      w[c] = _mm256_sub_ps(_mm256_i32gather_ps(v[c], J, 4), _mm256_i32gather_ps(v[c], I, 4));
    }
    __m256 force[3];
    packetForce(s, r, d, w, force);
    for (int c = 0; c < 3; ++c) _mm256_store_ps(out[c], force[c]);
    for (std::size_t l = 0; l < 8; ++l) {
      const int32_t a = s.i[r + l], b = s.j[r + l];
      for (int c = 0; c < 3; ++c) {
        f[c][a] += out[c][l];
        f[c][b] -= out[c][l];
      }
    }
  }
  for (; r < n; ++r) {
    const int32_t a = s.i[r], b = s.j[r];
    float dd[3], ww[3], l2 = 0.0f;
    for (int c = 0; c < 3; ++c) {
      dd[c] = x[c][b] - x[c][a], ww[c] = v[c][b] - v[c][a];
      l2 += dd[c] * dd[c];
    }
    const float len = std::sqrt(l2), rate = (dd[0] * ww[0] + dd[1] * ww[1] + dd[2] * ww[2]) / len;
    const float scale = (s.stiffness[r] * (len - s.restLength[r]) + s.damping[r] * rate) / len;
    for (int c = 0; c < 3; ++c) {
      f[c][a] += dd[c] * scale;
      f[c][b] -= dd[c] * scale;
    }
  }
}

void BM_StrutKernelFloat8(benchmark::State& state) {
  FloatCase fc;
  if (!floatCase(state, fc)) return;
  const Model& model = fc.model;
  const std::vector<Vec3>&x = fc.x, &v = fc.v;
  const FloatStruts& s = fc.struts;
  const std::size_t n = x.size();
  std::vector<float> xs[3], vs[3], fs[3];
  for (int c = 0; c < 3; ++c) {
    xs[c].resize(n), vs[c].resize(n), fs[c].assign(n, 0.0f);
    for (std::size_t k = 0; k < n; ++k) xs[c][k] = static_cast<float>(x[k][c]), vs[c][k] = static_cast<float>(v[k][c]);
  }
  const float* const xp[3] = {xs[0].data(), xs[1].data(), xs[2].data()};
  const float* const vp[3] = {vs[0].data(), vs[1].data(), vs[2].data()};
  float* const fp[3] = {fs[0].data(), fs[1].data(), fs[2].data()};
  for (auto _ : state) {
    strutsFloat8(s, xp, vp, fp);
    benchmark::DoNotOptimize(fp[0]);
    benchmark::ClobberMemory();
  }
  nsPer(state, "ns_per_strut", static_cast<double>(model.struts.size()));
}
BENCHMARK(BM_StrutKernelFloat8)->DenseRange(2, 6)->UseRealTime();

// The same with each vertex's position, velocity and force as four floats (x, y, z, unused): a
// strut end is one 16-byte load, and its force one 16-byte add, instead of three of each.
__attribute__((target("avx2,fma"))) void transpose8x4(const __m128 in[8], __m256 out[4]) {
  __m256 r[4];
  for (int k = 0; k < 4; ++k) r[k] = _mm256_set_m128(in[k + 4], in[k]);  // lanes k and k + 4
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  out[0] = _mm256_shuffle_ps(t0, t2, 0x44), out[1] = _mm256_shuffle_ps(t0, t2, 0xEE);
  out[2] = _mm256_shuffle_ps(t1, t3, 0x44), out[3] = _mm256_shuffle_ps(t1, t3, 0xEE);
}

__attribute__((target("avx2,fma"))) void strutsFloat4x8(const FloatStruts& s, const float* x, const float* v,
                                                        float* f) {
  const std::size_t n = s.i.size();
  std::size_t r = 0;
  for (; r + 8 <= n; r += 8) {
    __m128 a[8], b[8];
    __m256 d[4], w[4], t[4];
    for (int l = 0; l < 8; ++l) {
      a[l] = _mm_sub_ps(_mm_loadu_ps(x + 4 * s.j[r + l]), _mm_loadu_ps(x + 4 * s.i[r + l]));
      b[l] = _mm_sub_ps(_mm_loadu_ps(v + 4 * s.j[r + l]), _mm_loadu_ps(v + 4 * s.i[r + l]));
    }
    transpose8x4(a, d);
    transpose8x4(b, w);
    packetForce(s, r, d, w, t);
    t[3] = _mm256_setzero_ps();
    // Back to one (fx, fy, fz, 0) per strut: the same 8x4 transpose, read as 4x8.
    const __m256 t0 = _mm256_unpacklo_ps(t[0], t[1]), t1 = _mm256_unpackhi_ps(t[0], t[1]);
    const __m256 t2 = _mm256_unpacklo_ps(t[2], t[3]), t3 = _mm256_unpackhi_ps(t[2], t[3]);
    const __m256 q[4] = {_mm256_shuffle_ps(t0, t2, 0x44), _mm256_shuffle_ps(t0, t2, 0xEE),
                         _mm256_shuffle_ps(t1, t3, 0x44), _mm256_shuffle_ps(t1, t3, 0xEE)};
    for (int l = 0; l < 8; ++l) {
      const __m128 fl = l < 4 ? _mm256_castps256_ps128(q[l]) : _mm256_extractf128_ps(q[l - 4], 1);
      float* fi = f + 4 * s.i[r + l];
      float* fj = f + 4 * s.j[r + l];
      _mm_storeu_ps(fi, _mm_add_ps(_mm_loadu_ps(fi), fl));
      _mm_storeu_ps(fj, _mm_sub_ps(_mm_loadu_ps(fj), fl));
    }
  }
}

void BM_StrutKernelFloat4x8(benchmark::State& state) {
  FloatCase fc;
  if (!floatCase(state, fc)) return;
  const Model& model = fc.model;
  const std::vector<Vec3>&x = fc.x, &v = fc.v;
  const FloatStruts& s = fc.struts;
  std::vector<float> xs(4 * x.size(), 0.0f), vs(4 * x.size(), 0.0f), fs(4 * x.size(), 0.0f);
  for (std::size_t k = 0; k < x.size(); ++k) {
    for (int c = 0; c < 3; ++c)
      xs[4 * k + c] = static_cast<float>(x[k][c]), vs[4 * k + c] = static_cast<float>(v[k][c]);
  }
  // The price in accuracy, once: the largest difference from springy's kernel (doubles) over a
  // vertex's force, relative to the largest strut force (the packets cover all but the last
  // struts when their count is not a multiple of 8; those are left out of both).
  {
    const std::size_t whole = model.struts.size() / 8 * 8;
    std::vector<Vec3> f(x.size());
    applyStruts(model.struts.data(), Elements::range(0, whole), x.data(), v.data(), f.data());
    strutsFloat4x8(s, xs.data(), vs.data(), fs.data());
    double largest = 0.0, worst = 0.0;
    for (std::size_t k = 0; k < whole; ++k) {
      const Strut& st = model.struts[k];
      const Vec3 d = x[st.j] - x[st.i];
      const double l = length(d);
      largest =
          std::max(largest, std::fabs(st.stiffness * (l - st.restLength) + st.damping * dot(v[st.j] - v[st.i], d) / l));
    }
    for (std::size_t k = 0; k < x.size(); ++k) {
      const Vec3 single{fs[4 * k], fs[4 * k + 1], fs[4 * k + 2]};
      worst = std::max(worst, length(single - f[k]));
    }
    state.counters["error_vs_double"] = worst / largest;
    std::fill(fs.begin(), fs.end(), 0.0f);
  }
  for (auto _ : state) {
    strutsFloat4x8(s, xs.data(), vs.data(), fs.data());
    benchmark::DoNotOptimize(fs.data());
    benchmark::ClobberMemory();
  }
  nsPer(state, "ns_per_strut", static_cast<double>(model.struts.size() / 8 * 8));
}
BENCHMARK(BM_StrutKernelFloat4x8)->DenseRange(2, 6)->UseRealTime();

// And in doubles with a vertex as (x, y, z, unused): one 32-byte load an end and one 32-byte add
// for its force, four struts a packet: what the layout alone gives, at no cost in precision.
__attribute__((target("avx2,fma"))) void transpose4x4(const __m256d in[4], __m256d out[4]) {
  const __m256d t0 = _mm256_unpacklo_pd(in[0], in[1]), t1 = _mm256_unpackhi_pd(in[0], in[1]);
  const __m256d t2 = _mm256_unpacklo_pd(in[2], in[3]), t3 = _mm256_unpackhi_pd(in[2], in[3]);
  out[0] = _mm256_permute2f128_pd(t0, t2, 0x20), out[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
  out[2] = _mm256_permute2f128_pd(t0, t2, 0x31), out[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
}

__attribute__((target("avx2,fma"))) void strutsDouble4x4(const Strut* struts, std::size_t n, const double* x,
                                                         const double* v, double* f) {
  for (std::size_t r = 0; r + 4 <= n; r += 4) {
    __m256d a[4], b[4], d[4], w[4], t[4], q[4];
    for (int l = 0; l < 4; ++l) {
      const Strut& st = struts[r + static_cast<std::size_t>(l)];
      a[l] = _mm256_sub_pd(_mm256_loadu_pd(x + 4 * st.j), _mm256_loadu_pd(x + 4 * st.i));
      b[l] = _mm256_sub_pd(_mm256_loadu_pd(v + 4 * st.j), _mm256_loadu_pd(v + 4 * st.i));
    }
    transpose4x4(a, d);
    transpose4x4(b, w);
    const __m256d len =
        _mm256_sqrt_pd(_mm256_fmadd_pd(d[2], d[2], _mm256_fmadd_pd(d[1], d[1], _mm256_mul_pd(d[0], d[0]))));
    const __m256d inv = _mm256_div_pd(_mm256_set1_pd(1.0), len);
    __m256d u[3];
    for (int c = 0; c < 3; ++c) u[c] = _mm256_mul_pd(d[c], inv);
    const __m256d rate = _mm256_fmadd_pd(w[2], u[2], _mm256_fmadd_pd(w[1], u[1], _mm256_mul_pd(w[0], u[0])));
    const Strut *s0 = &struts[r], *s1 = s0 + 1, *s2 = s0 + 2, *s3 = s0 + 3;
    const __m256d k = _mm256_set_pd(s3->stiffness, s2->stiffness, s1->stiffness, s0->stiffness);
    const __m256d l0 = _mm256_set_pd(s3->restLength, s2->restLength, s1->restLength, s0->restLength);
    const __m256d c = _mm256_set_pd(s3->damping, s2->damping, s1->damping, s0->damping);
    const __m256d scale = _mm256_fmadd_pd(k, _mm256_sub_pd(len, l0), _mm256_mul_pd(c, rate));
    for (int m = 0; m < 3; ++m) t[m] = _mm256_mul_pd(u[m], scale);
    t[3] = _mm256_setzero_pd();
    transpose4x4(t, q);
    for (int l = 0; l < 4; ++l) {
      const Strut& st = struts[r + static_cast<std::size_t>(l)];
      double* fi = f + 4 * st.i;
      double* fj = f + 4 * st.j;
      _mm256_storeu_pd(fi, _mm256_add_pd(_mm256_loadu_pd(fi), q[l]));
      _mm256_storeu_pd(fj, _mm256_sub_pd(_mm256_loadu_pd(fj), q[l]));
    }
  }
}

void BM_StrutKernelDouble4x4(benchmark::State& state) {
  FloatCase fc;
  if (!floatCase(state, fc)) return;
  const std::size_t n = fc.x.size();
  std::vector<double> xs(4 * n, 0.0), vs(4 * n, 0.0), fs(4 * n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    for (int c = 0; c < 3; ++c) xs[4 * k + c] = fc.x[k][c], vs[4 * k + c] = fc.v[k][c];
  }
  for (auto _ : state) {
    strutsDouble4x4(fc.model.struts.data(), fc.model.struts.size(), xs.data(), vs.data(), fs.data());
    benchmark::DoNotOptimize(fs.data());
    benchmark::ClobberMemory();
  }
  nsPer(state, "ns_per_strut", static_cast<double>(fc.model.struts.size() / 4 * 4));
}
BENCHMARK(BM_StrutKernelDouble4x4)->DenseRange(2, 6)->UseRealTime();

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

// --- a prefactored global solve (issue 46): the step of projective dynamics or of Liu et al.'s
// fast mass-springs (2013) solves M/h^2 + sum_e k_e (e_i - e_j)(e_i - e_j)^T, a matrix fixed
// over the run, once per iteration for x, y and z. Its cost, beside BM_Forces at the same level,
// says how many explicit steps one iteration of such a method is worth on the same ball.

void BM_PrefactoredGlobalSolve(benchmark::State& state) {
  const Model model = ballModel(static_cast<int>(state.range(0)), false);
  const auto n = static_cast<Eigen::Index>(model.vertexCount());
  const double h = 1.0 / 60.0;
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index i = 0; i < n; ++i) entries.emplace_back(i, i, model.mass[static_cast<std::size_t>(i)] / (h * h));
  for (const Strut& e : model.struts) {
    const auto i = static_cast<Eigen::Index>(e.i), j = static_cast<Eigen::Index>(e.j);
    entries.emplace_back(i, i, e.stiffness);
    entries.emplace_back(j, j, e.stiffness);
    entries.emplace_back(i, j, -e.stiffness);
    entries.emplace_back(j, i, -e.stiffness);
  }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> factor(a);  // AMD ordering
  if (factor.info() != Eigen::Success) state.SkipWithError("the matrix is not positive definite");
  Eigen::MatrixXd rhs(n, 3), x(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3& p = model.restPosition[static_cast<std::size_t>(i)];
    rhs.row(i) << p.x, p.y, p.z;
  }
  for (auto _ : state) {
    x = factor.solve(rhs);
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
  state.counters["factor_nonzeros"] = static_cast<double>(factor.matrixL().nestedExpression().nonZeros());
  nsPer(state, "ns_per_vertex", static_cast<double>(model.vertexCount()));
}
BENCHMARK(BM_PrefactoredGlobalSolve)->DenseRange(2, 5)->UseRealTime();

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
Model gasBallModel() {
  Model model;
  BodyDesc desc = ballDesc(4);
  desc.strutPeriod = 0.015;
  desc.hingePeriod = 0.0;
  desc.volumePeriod = 0.01;
  addBody(model, desc);
  model.colliders.planes.push_back(PlaneCollider{{0, 0, 0}, {0, 1, 0}, 0.6, 0.3});
  return model;
}

void BM_GasBallStep(benchmark::State& state) {
  const Model model = gasBallModel();
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
  const Model model = gasBallModel();
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

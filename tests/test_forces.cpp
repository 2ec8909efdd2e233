// Struts and hinges: the laws the forces must obey.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "fixtures.h"
#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/shapes.h"
#include "sim/strut.h"

namespace springy {
namespace {

// Minus the gradient of the hinges' elastic energy (hingeEnergy) at x, by central differences
// of step h in every coordinate: what their elastic forces must equal.
std::vector<Vec3> minusEnergyGradient(const Hinge* hinges, std::size_t count, const std::vector<Vec3>& x, double h) {
  std::vector<Vec3> g(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      std::vector<Vec3> xp = x, xm = x;
      xp[i][c] += h;
      xm[i][c] -= h;
      g[i][c] = -(hingeEnergy(hinges, 0, count, xp.data()) - hingeEnergy(hinges, 0, count, xm.data())) / (2 * h);
    }
  }
  return g;
}

// Measures period (mean time between upward zero crossings of the extension) and the decay
// time constant (from the log of successive peak amplitudes) of a strut's oscillation.
struct Oscillation {
  double period, decay;
};
Oscillation measureStrut(World& world, double restLength, double seconds) {
  std::vector<double> crossings, peakTimes, peaks;
  double prev = length(world.positions()[1] - world.positions()[0]) - restLength, prevPrev = prev;
  while (world.time() < seconds) {
    world.step();
    const double ext = length(world.positions()[1] - world.positions()[0]) - restLength;
    if (prev < 0.0 && ext >= 0.0) crossings.push_back(world.time() - world.dt() * ext / (ext - prev));
    if (prev > prevPrev && prev >= ext && prev > 0.0) {
      // Parabolic interpolation of the peak through the last three samples.
      const double denom = prevPrev - 2 * prev + ext;
      const double off = denom != 0.0 ? 0.5 * (prevPrev - ext) / denom : 0.0;
      peaks.push_back(prev - 0.25 * (prevPrev - ext) * off);
      peakTimes.push_back(world.time() - world.dt() * (1.0 - off));
    }
    prevPrev = prev;
    prev = ext;
  }
  Oscillation o{};
  o.period = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  // ln(A) falls linearly with slope -1/T.
  o.decay = (peakTimes.back() - peakTimes.front()) / std::log(peaks.front() / peaks.back());
  return o;
}

TEST(Strut, OneFreeMassOscillatesWithPeriodPAndDecayT) {
  // The seed's conversion (docs/model.md eq. S22-S25) is for a mass m on the spring against a fixed end.
  const double m = 0.5, P = 0.2, T = 0.5, L = 1.0;
  Model model = test::strutModel(m, m, L, stiffnessFromPeriod(m, P), dampingFromDecay(m, T), /*pinFirst=*/true);
  World world(std::move(model), Integrator::RK4, 1e-4);
  std::vector<Vec3> x = world.positions();
  x[1].x += 0.05;
  world.setState(x, world.velocities());
  const Oscillation o = measureStrut(world, L, 1.5);
  // The damped period is P / sqrt(1 - (P / (2 pi T))^2); T is exact.
  const double dampedPeriod = P / std::sqrt(1.0 - std::pow(P / (2 * kPi * T), 2));
  EXPECT_NEAR(o.period, dampedPeriod, 0.01 * P);
  EXPECT_NEAR(o.period, P, 0.01 * P);
  EXPECT_NEAR(o.decay, T, 0.01 * T);
}

TEST(Strut, TwoFreeMassesOscillateAboutTheirCentreWithTheReducedMass) {
  // Two free masses m on the same spring: the reduced mass m/2 gives period P / sqrt(2) and
  // decay time T / 2. This is why P and T are documented as "against a fixed end".
  const double m = 0.5, P = 0.2, T = 0.5, L = 1.0;
  Model model = test::strutModel(m, m, L, stiffnessFromPeriod(m, P), dampingFromDecay(m, T), false);
  World world(std::move(model), Integrator::RK4, 1e-4);
  std::vector<Vec3> x = world.positions();
  x[0].x -= 0.025;
  x[1].x += 0.025;
  world.setState(x, world.velocities());
  const Oscillation o = measureStrut(world, L, 0.8);
  EXPECT_NEAR(o.period, P / std::sqrt(2.0), 0.01 * P / std::sqrt(2.0));
  EXPECT_NEAR(o.decay, T / 2, 0.01 * T / 2);
}

TEST(Strut, ForcesFollowHookeAndDashpotLaws) {
  const Strut s{0, 1, 2.0, 10.0, 3.0};
  const Vec3 x[2] = {{0, 0, 0}, {0, 2.5, 0}};
  const Vec3 v[2] = {{0, 0, 0}, {1.0, 0.2, 0}};  // only the 0.2 along the strut is damped
  Vec3 f[2] = {};
  applyStruts(&s, Elements::range(0, 1), x, v, f);
  EXPECT_DOUBLE_EQ(f[0].y, 10.0 * 0.5 + 3.0 * 0.2);
  EXPECT_DOUBLE_EQ(f[1].y, -f[0].y);
  EXPECT_DOUBLE_EQ(f[0].x, 0.0);
}

class HingeAngles : public ::testing::TestWithParam<double> {};

TEST_P(HingeAngles, ForcesSumToZeroWithZeroTorque) {
  const double theta = GetParam();
  Model model = test::hingeModel(0.3, 2.0, 0.7, false);
  std::vector<Vec3> x = test::hingePositions(theta);
  x[3] += Vec3{0.1, 0.05, -0.2};  // asymmetric
  const std::vector<Vec3> v = {{0.3, -0.2, 0.1}, {-0.5, 0.4, 0.2}, {0.1, 0.9, -1.0}, {0.7, -0.3, 0.4}};
  std::vector<Vec3> f(4);
  applyHingesDerivingTerms(model.hinges.data(), 0, 1, x.data(), v.data(), f.data());
  Vec3 sum, torque;
  double scale = 0.0;
  for (int i = 0; i < 4; ++i) {
    sum += f[i];
    torque += cross(x[i] - Vec3{3, -2, 5}, f[i]);  // about an arbitrary point
    scale += length(f[i]);
  }
  ASSERT_GT(scale, 0.1);
  EXPECT_LT(length(sum), 1e-12 * scale);
  EXPECT_LT(length(torque), 1e-11 * scale);
}

TEST_P(HingeAngles, ElasticForceIsMinusTheEnergyGradient) {
  // With d_theta = 0, f = -grad(1/2 k (theta - theta0)^2): compare with central differences.
  const double theta = GetParam();
  Model model = test::hingeModel(0.3, 2.0, 0.0, false);
  std::vector<Vec3> x = test::hingePositions(theta);
  x[2] += Vec3{0.05, -0.1, 0.02};
  std::vector<Vec3> v(4), f(4);
  applyHingesDerivingTerms(model.hinges.data(), 0, 1, x.data(), v.data(), f.data());
  const std::vector<Vec3> expected = minusEnergyGradient(model.hinges.data(), 1, x, 1e-6);
  for (int i = 0; i < 4; ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[i][c], expected[i][c], 1e-6) << "vertex " << i << " component " << c;
  }
}

TEST_P(HingeAngles, RestAngleMatchesTheForceConvention) {
  // A hinge built at its rest configuration exerts no force (the seed's rest angle was
  // mirrored, so every hinge started pre-stressed).
  const double theta = GetParam();
  Model model = test::hingeModel(theta, 5.0, 1.0, false);
  EXPECT_NEAR(dihedralAngle(model.restPosition[0], model.restPosition[1], model.restPosition[2], model.restPosition[3]),
              theta, 1e-12);
  std::vector<Vec3> v(4), f(4);
  applyHingesDerivingTerms(model.hinges.data(), 0, 1, model.restPosition.data(), v.data(), f.data());
  for (const Vec3& fi : f) EXPECT_LT(length(fi), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Angles, HingeAngles, ::testing::Values(-2.5, -1.0, -0.2, 0.0, 0.4, 1.2, 2.8));

TEST(Hinge, ConvexFoldHasPositiveAngleAndWrapsAtPi) {
  EXPECT_GT(dihedralAngle({0, 0, 0}, {1, 0, 0}, {0.4, 1, -0.3}, {0.6, -1, -0.3}), 0.0);
  EXPECT_NEAR(angleDifference(3.1, -3.1), 6.2 - 2 * kPi, 1e-12);
  EXPECT_NEAR(angleDifference(-3.1, 3.1), 2 * kPi - 6.2, 1e-12);
}

TEST(Hinge, BentHingeReturnsToRestAngle) {
  const double rest = 0.5;
  Model model = test::hingeModel(rest, 0.5, 0.8, true, 200.0, 2.0);
  World world(std::move(model), Integrator::RK4, 1e-3);
  world.setState(test::hingePositions(1.3), std::vector<Vec3>(4));
  for (int s = 0; s < 20000; ++s) world.step();
  const auto& x = world.positions();
  EXPECT_NEAR(dihedralAngle(x[0], x[1], x[2], x[3]), rest, 1e-3);
}

TEST(Hinge, RigidMotionGivesNoForceEvenWithDamping) {
  // A bent body moving rigidly (translation + rotation) feels no strut or hinge force.
  TriMesh mesh = makeIcosphere(1.0, 1);
  for (Vec3& p : mesh.positions) p.y *= 0.6;  // not a sphere: hinges at several angles
  Model model;
  model.gravity = {};
  BodyDesc desc;
  desc.name = "rigid";
  desc.mesh = mesh;
  desc.mass = 2.0;
  addBody(model, desc);
  ASSERT_FALSE(model.hinges.empty());
  World world(std::move(model), Integrator::RK4, 1e-3);
  const Vec3 velocity{1.0, -2.0, 0.5}, omega{0.3, 1.1, -0.7}, c{0.2, 0.1, -0.3};
  std::vector<Vec3> v(world.positions().size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = velocity + cross(omega, world.positions()[i] - c);
  std::vector<Vec3> f(v.size());
  world.computeForces(world.positions().data(), v.data(), 0.0, f.data());
  double biggestSpringForce = 0.0;
  for (const Strut& s : world.model().struts) biggestSpringForce = std::max(biggestSpringForce, s.damping * length(velocity));
  for (const Vec3& fi : f) EXPECT_LT(length(fi), 1e-9 * biggestSpringForce);
}

}  // namespace
}  // namespace springy

namespace springy {
namespace {

TEST(Hinge, CrushedFaceFadesOutConservatively) {
  // A wing vertex pushed toward the hinge line: the exact gradient grows as 1/|r|. Below a
  // fifth of its rest lever the hinge fades out (energy 1/2 k delta^2 S(|r|/minLever)), so the
  // force stays finite, is exactly minus the gradient of that energy (no energy can be pumped
  // in through a crushed face), sums to zero, and the energy goes continuously to zero as the
  // wing reaches the line, where the angle itself is undefined.
  const std::vector<Vec3> rest = test::hingePositions(0.6);
  HingeGeometry g0;
  ASSERT_TRUE(hingeGeometry(rest[0], rest[1], rest[2], rest[3], g0));
  Hinge h{{0, 1, 2, 3}, g0.theta, 3.0, 0.0, {0.2 * g0.leverLeft, 0.2 * g0.leverRight}};
  const Vec3 foot = rest[0] + (rest[1] - rest[0]) * 0.4;  // a point on the hinge line
  const Vec3 h01 = normalized(rest[1] - rest[0]);
  const Vec3 away = normalized((rest[2] - foot) - h01 * dot(rest[2] - foot, h01));  // perpendicular to the line
  double previous = 0.0;
  for (double fraction : {1.5, 1.0, 0.8, 0.5, 0.2, 1e-3, 1e-7}) {  // lever / minLever
    std::vector<Vec3> x = rest;
    x[2] = foot + away * (fraction * h.minLever[0]);  // lever = fraction * minLever
    HingeGeometry g;
    ASSERT_TRUE(hingeGeometry(x[0], x[1], x[2], x[3], g));
    EXPECT_NEAR(g.leverLeft, fraction * h.minLever[0], 1e-9 * h.minLever[0]);
    std::vector<Vec3> v(4), f(4);
    applyHingesDerivingTerms(&h, 0, 1, x.data(), v.data(), f.data());
    double largest = 0.0;
    Vec3 sum;
    for (const Vec3& fi : f) {
      ASSERT_TRUE(isFinite(fi));
      largest = std::max(largest, length(fi));
      sum += fi;
    }
    EXPECT_LT(length(sum), 1e-9 * largest + 1e-15) << fraction;
    EXPECT_LT(largest, 10.0 * h.stiffness * 3.2 / h.minLever[0]) << fraction;  // bounded by ~k pi / minLever
    // f = -grad E, by central differences of hingeEnergy (every coordinate of every vertex).
    const std::vector<Vec3> expected = minusEnergyGradient(&h, 1, x, 1e-7 * h.minLever[0]);
    for (std::size_t i = 0; i < 4; ++i) {
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[i][c], expected[i][c], 1e-5 * (largest + 1.0)) << fraction << " vertex " << i;
    }
    const double energy = hingeEnergy(&h, 0, 1, x.data());
    if (fraction < 1.0) {
      EXPECT_LT(energy, 0.5 * h.stiffness * 10.0) << fraction;  // below 1/2 k pi^2
    }
    previous = energy;
  }
  EXPECT_LT(previous, 1e-12);  // at a lever of 1e-7 minLever: faded out
}

TEST(Hinge, FastKernelMatchesTheReferenceFormulas) {
  // The force kernel rearranges hingeGeometry's formulas for speed (unnormalised normals, the
  // angle difference from its sine and cosine, a series for small differences). Compared with
  // the reference f_i = -(k (theta - theta0) + d dtheta/dt) g_i over random hinges bent a
  // little (series branch), a lot (atan2 branch) and across +-pi, it must agree to rounding;
  // with a crushed wing (the fading guard) it must be minus the gradient of the faded energy.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int seriesCases = 0, atanCases = 0, guardCases = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double rest = 3.0 * u(rng);
    const std::vector<Vec3> restX = test::hingePositions(rest);
    HingeGeometry g0;
    ASSERT_TRUE(hingeGeometry(restX[0], restX[1], restX[2], restX[3], g0));
    const Hinge h{{0, 1, 2, 3}, g0.theta, 2.0 + u(rng), 0.5 + 0.4 * u(rng), {0.2 * g0.leverLeft, 0.2 * g0.leverRight}};
    const double bend = trial % 3 == 0 ? 0.2 * u(rng) : 2.5 * u(rng);
    std::vector<Vec3> x = test::hingePositions(rest + bend), v(4);
    for (Vec3& p : x) p += Vec3{u(rng), u(rng), u(rng)} * 0.05;
    for (Vec3& w : v) w = Vec3{u(rng), u(rng), u(rng)};
    if (trial % 50 == 0) x[2] = x[0] + (x[1] - x[0]) * 0.4 + Vec3{0, 1e-3, 1e-3} * u(rng);  // crushed
    HingeGeometry g;
    ASSERT_TRUE(hingeGeometry(x[0], x[1], x[2], x[3], g));
    const double delta = angleDifference(g.theta, h.restAngle);
    (std::fabs(delta) < 0.24 ? seriesCases : atanCases)++;
    if (g.leverLeft < h.minLever[0] || g.leverRight < h.minLever[1]) {
      // A crushed face: the hinge fades out, and its elastic force is minus the gradient of the
      // faded energy (hingeEnergy), by central differences.
      guardCases++;
      std::vector<Vec3> still(4), f(4);
      applyHingesDerivingTerms(&h, 0, 1, x.data(), still.data(), f.data());
      double largest = 0.0;
      for (const Vec3& fi : f) largest = std::max(largest, length(fi));
      const std::vector<Vec3> expected = minusEnergyGradient(&h, 1, x, 1e-7);
      for (std::size_t i = 0; i < 4; ++i) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[i][c], expected[i][c], 1e-5 * (largest + 1.0)) << "trial " << trial;
      }
      continue;
    }
    double rate = 0.0;
    for (int i = 0; i < 4; ++i) rate += dot(g.grad[i], v[static_cast<std::size_t>(i)]);
    const double torque = h.stiffness * delta + h.damping * rate;
    std::vector<Vec3> f(4);
    applyHingesDerivingTerms(&h, 0, 1, x.data(), v.data(), f.data());
    double scale = 0.0;
    for (int i = 0; i < 4; ++i) scale = std::max(scale, length(g.grad[i] * torque));
    for (int i = 0; i < 4; ++i) {
      EXPECT_LT(length(f[static_cast<std::size_t>(i)] + g.grad[i] * torque), 1e-12 * scale + 1e-300)
          << "trial " << trial << " vertex " << i << " delta " << delta;
    }
  }
  EXPECT_GT(seriesCases, 500);
  EXPECT_GT(atanCases, 500);
  EXPECT_GT(guardCases, 10);
}

}  // namespace
}  // namespace springy

namespace springy {
namespace {

TEST(Model, VerticesAreRenumberedInSpatialOrderKeepingTheMesh) {
  // addBody numbers a body's vertices in slabs along its longest side; the model must still be
  // the mesh's: the same positions, faces with the same orientation, one strut per mesh edge.
  const TriMesh mesh = makeIcosphere(1.0, 5);  // 10242 vertices
  Model model;
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = mesh;
  desc.mass = 1.0;
  desc.hingePeriod = 0.5;
  addBody(model, desc);
  const std::vector<uint32_t>& mv = model.bodies[0].modelVertex;
  const std::size_t n = mesh.positions.size();
  ASSERT_EQ(mv.size(), n);
  std::vector<bool> seen(n, false);
  for (std::size_t k = 0; k < n; ++k) {
    ASSERT_LT(mv[k], n);
    ASSERT_FALSE(seen[mv[k]]) << "modelVertex is not a permutation";
    seen[mv[k]] = true;
    ASSERT_EQ(model.restPosition[mv[k]], mesh.positions[k]) << "mesh vertex " << k;
  }
  // The faces are the mesh's, each with its corners in the mesh's order (its orientation),
  // listed by their lowest vertex so that a thread's faces read a compact stretch.
  ASSERT_EQ(model.faces.size(), mesh.triangles.size());
  std::vector<Triangle> expected;
  for (const Triangle& t : mesh.triangles) expected.push_back({mv[t[0]], mv[t[1]], mv[t[2]]});
  std::vector<Triangle> faces = model.faces;
  const auto lowest = [](const Triangle& t) { return std::min({t[0], t[1], t[2]}); };
  for (std::size_t f = 1; f < faces.size(); ++f) {
    ASSERT_LE(lowest(faces[f - 1]), lowest(faces[f])) << "face " << f;
  }
  std::sort(expected.begin(), expected.end());
  std::sort(faces.begin(), faces.end());
  EXPECT_EQ(faces, expected);
  std::set<std::pair<uint32_t, uint32_t>> edges, struts;
  for (const Triangle& t : mesh.triangles) {
    for (int c = 0; c < 3; ++c) {
      const uint32_t a = mv[t[c]], b = mv[t[(c + 1) % 3]];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  }
  for (const Strut& s : model.struts) struts.insert({std::min(s.i, s.j), std::max(s.i, s.j)});
  EXPECT_EQ(struts, edges);
  EXPECT_EQ(model.struts.size(), edges.size());
  EXPECT_EQ(model.hinges.size(), edges.size());
  double total = 0.0;
  for (double m : model.mass) total += m;
  EXPECT_NEAR(total, 1.0, 1e-12);

  // Spatial: halving the index range cuts few struts, so each of two threads owns a compact
  // piece; the subdivision's own numbering (midpoints of the last level last) cuts many.
  const auto cut = [&](auto meshIndex) {
    std::size_t count = 0;
    for (const auto& [a, b] : edges) count += (meshIndex(a) < n / 2) != (meshIndex(b) < n / 2);
    return static_cast<double>(count);
  };
  std::vector<uint32_t> toMesh(n);
  for (uint32_t k = 0; k < n; ++k) toMesh[mv[k]] = k;
  const double spatialCut = cut([](uint32_t i) { return i; });
  const double meshCut = cut([&](uint32_t i) { return toMesh[i]; });
  EXPECT_LT(spatialCut, 0.02 * static_cast<double>(edges.size()));
  EXPECT_LT(spatialCut, 0.1 * meshCut);

  // Slabs: wherever the index range is cut (here for 2, 3 and 4 threads), the vertices the
  // edges reach across the cut are a short run of indices next to it, not spread over the
  // other range: a thread reads a few cache lines of its neighbour's vertices, not one line per
  // vertex. For this ball a run is about two rings of vertices (~300 of 10242).
  for (const std::size_t parts : {2u, 3u, 4u}) {
    for (std::size_t p = 1; p < parts; ++p) {
      const uint32_t s = static_cast<uint32_t>(n * p / parts);
      uint32_t first = s, last = s;  // the reached vertices span [first, last]
      for (const auto& [a, b] : edges) {
        if ((a < s) == (b < s)) continue;
        first = std::min(first, std::min(a, b));
        last = std::max(last, std::max(a, b));
      }
      EXPECT_LT(static_cast<double>(last - first), 0.06 * static_cast<double>(n))
          << parts << " parts, cut at " << s << ": reached vertices " << first << " to " << last;
    }
  }
}

}  // namespace
}  // namespace springy

namespace springy {
namespace {

// The packet kernels' test body: a level-3 icosphere, 1 m across, 1 kg, with desc's stiffness.
Model packetBall(BodyDesc desc) {
  desc.name = "ball";
  desc.mesh = makeIcosphere(1.0, 3);
  desc.mass = 1.0;
  Model model;
  addBody(model, desc);
  return model;
}

// A deformed, moving state: rest positions moved by up to `amplitude` per axis, velocities up
// to 1 m/s per axis, from rng.
void shake(const Model& model, std::mt19937_64& rng, double amplitude, std::vector<Vec3>& x, std::vector<Vec3>& v) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  x = model.restPosition;
  v.assign(x.size(), Vec3{});
  for (Vec3& p : x) p += Vec3{u(rng), u(rng), u(rng)} * amplitude;
  for (Vec3& w : v) w = Vec3{u(rng), u(rng), u(rng)};
}

TEST(Strut, FourStrutPacketsEqualTheOneAtATimeKernelExactly) {
  // applyStruts computes struts four at a time in vector lanes; the forces must be
  // bit-identical to the one-strut kernel's (a range of one strut), summed in the same order,
  // also through a thread's list with masks: on a deformed, moving icosphere with one strut
  // whose ends coincide (skipped, no force).
  BodyDesc desc;
  desc.strutPeriod = 0.05;
  desc.strutDecay = 0.2;
  const Model model = packetBall(desc);
  std::mt19937_64 rng(5);
  std::vector<Vec3> x, v;
  shake(model, rng, 0.05, x, v);
  const Strut& collapsed = model.struts[42];
  x[collapsed.j] = x[collapsed.i];
  std::vector<Vec3> packets(x.size()), single(x.size());
  applyStruts(model.struts.data(), Elements::range(0, model.struts.size()), x.data(), v.data(), packets.data());
  for (std::size_t s = 0; s < model.struts.size(); ++s) {
    applyStruts(model.struts.data(), Elements::range(s, s + 1), x.data(), v.data(), single.data());
  }
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(packets[i], single[i]) << "vertex " << i;
  // The collapsed strut adds nothing: its ends' forces are those of their other struts.
  std::vector<Vec3> without(x.size());
  for (std::size_t s = 0; s < model.struts.size(); ++s) {
    if (s != 42) applyStruts(model.struts.data(), Elements::range(s, s + 1), x.data(), v.data(), without.data());
  }
  EXPECT_EQ(single[collapsed.i], without[collapsed.i]);
  // A thread's list (every third strut, alternating masks) against one strut at a time.
  std::vector<ElementRef> list;
  for (uint32_t s = 0; s < model.struts.size(); s += 3) list.push_back({s, 1u + (s / 3) % 3});
  std::vector<Vec3> owned(x.size()), reference(x.size());
  applyStruts(model.struts.data(), Elements::owned(list), x.data(), v.data(), owned.data());
  for (const ElementRef& r : list)
    applyStruts(model.struts.data(), Elements::owned(&r, 1), x.data(), v.data(), reference.data());
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(owned[i], reference[i]) << "vertex " << i;
}

TEST(Hinge, FourHingePacketsEqualTheOneAtATimeKernelExactly) {
  // applyHinges computes hinges four at a time in vector lanes; its forces must be bit-identical
  // to the one-hinge kernel's (which a range of one hinge uses), summed in the same order: on a
  // bent, moving icosphere (hinges share vertices), with some faces crushed past the lever
  // guard, some hinges bent past the series branch, and one degenerate (skipped) hinge.
  BodyDesc desc;
  desc.hingePeriod = 0.3;
  desc.hingeDecay = 0.5;
  const Model model = packetBall(desc);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> x, v;
  shake(model, rng, 0.08, x, v);  // bends hinges up to ~30 degrees
  for (std::size_t k = 0; k < model.hinges.size(); k += 37) {  // crush some faces
    const Hinge& h = model.hinges[k];
    x[h.v[2]] = x[h.v[0]] + (x[h.v[1]] - x[h.v[0]]) * 0.5 + Vec3{1e-3, 1e-3, 0.0} * u(rng);
  }
  const Hinge& flat = model.hinges[101];
  x[flat.v[3]] = x[flat.v[0]] + (x[flat.v[1]] - x[flat.v[0]]) * 0.25;  // wing on the hinge line
  std::vector<HingeTerms> terms;
  for (const Hinge& h : model.hinges) terms.push_back(hingeTerms(h));
  std::vector<Vec3> packets(x.size()), single(x.size());
  applyHinges(model.hinges.data(), terms.data(), Elements::range(0, model.hinges.size()), x.data(), v.data(),
              packets.data());
  for (std::size_t k = 0; k < model.hinges.size(); ++k) {
    applyHinges(model.hinges.data(), terms.data(), Elements::range(k, k + 1), x.data(), v.data(), single.data());
  }
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(packets[i], single[i]) << "vertex " << i;
    nonzero += length(single[i]) > 0.0;
  }
  EXPECT_EQ(nonzero, x.size());
  // The same through a thread's reference list, with some corners masked out.
  std::vector<ElementRef> list;
  for (uint32_t k = 0; k < model.hinges.size(); k += 2) list.push_back({k, (k % 3 == 0) ? 0xFu : 0x5u});
  std::vector<Vec3> owned(x.size()), ownedSingle(x.size());
  applyHinges(model.hinges.data(), terms.data(), Elements::owned(list), x.data(), v.data(), owned.data());
  for (const ElementRef& r : list) {
    applyHinges(model.hinges.data(), terms.data(), Elements::owned(&r, 1), x.data(), v.data(), ownedSingle.data());
  }
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(owned[i], ownedSingle[i]) << "vertex " << i;
}

TEST(Wind, FourFacePacketsEqualTheOneAtATimeKernelExactly) {
  // applyWindPressure computes faces four at a time in vector lanes; each face's force must be
  // bit-identical to the one-face kernel's (a range of one face), added in the same order, also
  // through a thread's list with masks: on a deformed, moving closed ball (pushed on its
  // windward side only) and an open sheet (pushed from either side), with one face crushed to
  // no area (no force).
  BodyDesc ball;
  ball.name = "ball";
  ball.mesh = makeIcosphere(1.0, 2);
  ball.mass = 1.0;
  BodyDesc sheet;
  sheet.name = "sheet";
  sheet.mesh = makeCloth(1.0, 1.0, 7, 7);
  sheet.mass = 0.2;
  sheet.material = MaterialModel::Body;
  sheet.cloth = true;
  Model model;
  addBody(model, ball);
  addBody(model, sheet);
  ASSERT_TRUE(model.bodies[1].open);
  model.wind = Wind{};
  model.wind->pressure = 1.7;
  std::mt19937_64 rng(13);
  std::vector<Vec3> x, v;
  shake(model, rng, 0.04, x, v);
  const Triangle& crushed = model.faces[model.bodies[1].firstFace + 5];
  x[crushed[1]] = x[crushed[0]], x[crushed[2]] = x[crushed[0]];
  const Vec3 air{3.0, 0.5, -1.0};
  const std::size_t faces = model.faces.size();
  std::vector<Vec3> packets(x.size()), single(x.size());
  applyWindPressure(model, Elements::range(0, faces), air, x.data(), v.data(), packets.data());
  for (std::size_t k = 0; k < faces; ++k) {
    applyWindPressure(model, Elements::range(k, k + 1), air, x.data(), v.data(), single.data());
  }
  std::size_t pushed[2] = {0, 0};
  for (std::size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(packets[i], single[i]) << "vertex " << i;
    pushed[model.body[i]] += length(single[i]) > 0.0;
  }
  // Some of the ball is leeward and unpushed; the sheet is pushed everywhere.
  EXPECT_GT(pushed[0], 0u);
  EXPECT_LT(pushed[0], model.bodies[0].vertexCount);
  EXPECT_EQ(pushed[1], model.bodies[1].vertexCount);
  std::vector<ElementRef> list;
  for (uint32_t k = 0; k < faces; k += 2) list.push_back({k, (k % 3 == 0) ? 0x7u : 0x5u});
  std::vector<Vec3> owned(x.size()), ownedSingle(x.size());
  applyWindPressure(model, Elements::owned(list), air, x.data(), v.data(), owned.data());
  for (const ElementRef& r : list) {
    applyWindPressure(model, Elements::owned(&r, 1), air, x.data(), v.data(), ownedSingle.data());
  }
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(owned[i], ownedSingle[i]) << "vertex " << i;
}

}  // namespace
}  // namespace springy

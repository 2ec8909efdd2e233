#include "sim/stability.h"

#include <algorithm>
#include <cmath>

#include "sim/error.h"
#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/shapes.h"

namespace springy {
namespace {

struct State {
  double x, v;
};

// One step of each integrator on the scalar mode, mirroring World::step.
State stepMode(Integrator integrator, double w2, double g, double h, State s) {
  auto a = [&](double x, double v) { return -w2 * x - g * v; };
  switch (integrator) {
    case Integrator::ExplicitEuler: return {s.x + h * s.v, s.v + h * a(s.x, s.v)};
    case Integrator::SymplecticEuler: {
      const double v = s.v + h * a(s.x, s.v);
      return {s.x + h * v, v};
    }
    case Integrator::VelocityVerlet: {
      const double a0 = a(s.x, s.v);
      const double x = s.x + h * s.v + 0.5 * h * h * a0;
      const double a1 = a(x, s.v + h * a0);
      return {x, s.v + 0.5 * h * (a0 + a1)};
    }
    case Integrator::Leapfrog: {
      const double a0 = a(s.x, s.v);
      const double vh = s.v + 0.5 * h * a0;
      const double x = s.x + h * vh;
      const double a1 = a(x, vh + 0.5 * h * a0);
      return {x, vh + 0.5 * h * a1};
    }
    case Integrator::RK4: {
      const double k1x = s.v, k1v = a(s.x, s.v);
      const double k2x = s.v + 0.5 * h * k1v, k2v = a(s.x + 0.5 * h * k1x, s.v + 0.5 * h * k1v);
      const double k3x = s.v + 0.5 * h * k2v, k3v = a(s.x + 0.5 * h * k2x, s.v + 0.5 * h * k2v);
      const double k4x = s.v + h * k3v, k4v = a(s.x + h * k3x, s.v + h * k3v);
      return {s.x + h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x), s.v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)};
    }
    case Integrator::BackwardEuler: {
      // (1 + h g + h^2 w2) v1 = v - h w2 x ; x1 = x + h v1
      const double v = (s.v - h * w2 * s.x) / (1 + h * g + h * h * w2);
      return {s.x + h * v, v};
    }
  }
  return s;
}

bool stableAt(Integrator integrator, double omega, double gamma, double h, double horizon) {
  const double rho = amplification(integrator, omega, gamma, h);
  if (!std::isfinite(rho)) return false;
  if (rho <= 1.0) return true;
  return std::log(rho) * std::max(1.0, horizon / h) <= 0.5 * std::log(2.0);
}

}  // namespace

double amplification(Integrator integrator, double omega, double gamma, double h) {
  const double w2 = omega * omega;
  const State c0 = stepMode(integrator, w2, gamma, h, {1, 0});
  const State c1 = stepMode(integrator, w2, gamma, h, {0, 1});
  // Eigenvalues of [[c0.x, c1.x], [c0.v, c1.v]].
  // ((a - d)/2)^2 + b c rather than tr^2/4 - det: no cancellation when both are near 1.
  const double tr = c0.x + c1.v, det = c0.x * c1.v - c1.x * c0.v;
  const double half = 0.5 * (c0.x - c1.v);
  const double disc = half * half + c1.x * c0.v;
  if (disc < 0) return std::sqrt(std::max(det, 0.0));
  const double s = std::sqrt(disc);
  return std::max(std::fabs(0.5 * tr + s), std::fabs(0.5 * tr - s));
}

double criticalStep(Integrator integrator, double omega, double gamma, double horizon) {
  const double rate = std::max(omega, gamma);
  if (integrator == Integrator::BackwardEuler || !(rate > 0.0)) return std::numeric_limits<double>::infinity();
  // Scan upward from a surely stable step for the first unstable one, then bisect.
  double lo = 1e-6 / rate;
  if (!stableAt(integrator, omega, gamma, lo, horizon)) return lo;
  double hi = lo;
  while (stableAt(integrator, omega, gamma, hi, horizon)) {
    lo = hi;
    hi *= 1.25;
    if (hi > 1e4 / rate) return std::numeric_limits<double>::infinity();
  }
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (lo + hi);
    (stableAt(integrator, omega, gamma, mid, horizon) ? lo : hi) = mid;
  }
  return lo;
}

std::vector<RowBound> gershgorinRows(const Model& model, const Vec3* x, uint32_t body) {
  const BodyInfo& info = model.bodies[body];
  std::vector<RowBound> rows(info.vertexCount);
  for (uint32_t k = 0; k < info.vertexCount; ++k) {
    rows[k].vertex = info.firstVertex + k;
    rows[k].drag = model.drag + info.deformationDamping;  // both -c m_i on the diagonal (the
                                                          // rigid part only lowers the bound)
  }
  auto free = [&](uint32_t v) { return model.invMass[v] != 0.0; };
  auto row = [&](uint32_t v) -> RowBound& { return rows[v - info.firstVertex]; };
  for (uint32_t s = info.firstStrut; s < info.firstStrut + info.strutCount; ++s) {
    const Strut& st = model.struts[s];
    const double l = length(x[st.j] - x[st.i]);
    const double stretch = l > 0.0 ? std::max(1.0, std::fabs(1.0 - st.restLength / l)) : 1.0;
    const double k = st.stiffness * stretch, d = st.damping;
    const double mi = model.mass[st.i], mj = model.mass[st.j], mij = std::sqrt(mi * mj);
    if (free(st.i)) {
      row(st.i).strutStiffness += k / mi + (free(st.j) ? k / mij : 0.0);
      row(st.i).strutDamping += d / mi + (free(st.j) ? d / mij : 0.0);
    }
    if (free(st.j)) {
      row(st.j).strutStiffness += k / mj + (free(st.i) ? k / mij : 0.0);
      row(st.j).strutDamping += d / mj + (free(st.i) ? d / mij : 0.0);
    }
  }
  HingeGeometry g;
  for (uint32_t h = info.firstHinge; h < info.firstHinge + info.hingeCount; ++h) {
    const Hinge& hg = model.hinges[h];
    if (!hingeGeometry(x[hg.v[0]], x[hg.v[1]], x[hg.v[2]], x[hg.v[3]], g, hg.minLever[0], hg.minLever[1])) continue;
    double w[4];  // |g_i| / sqrt(m_i), 0 for pinned vertices
    for (int a = 0; a < 4; ++a) w[a] = free(hg.v[a]) ? length(g.grad[a]) / std::sqrt(model.mass[hg.v[a]]) : 0.0;
    const double sum = w[0] + w[1] + w[2] + w[3];
    for (int a = 0; a < 4; ++a) {
      if (!free(hg.v[a])) continue;
      row(hg.v[a]).hingeStiffness += hg.stiffness * w[a] * sum;
      row(hg.v[a]).hingeDamping += hg.damping * w[a] * sum;
    }
  }
  if (info.gasPressure > 0.0) {
    const double sum = volumeModeSum(model, info, x);
    const double volume = enclosedVolume(model, body, x);
    const double w2 = volume > 0.0 ? info.gasPressure * info.restVolume / (volume * volume) * sum : 0.0;
    for (RowBound& r : rows) r.gasStiffness = w2;
  }
  return rows;
}

BodyStability bodyStability(const std::vector<RowBound>& rows, Integrator integrator, double horizon,
                            const ParameterScale& scale) {
  BodyStability out;
  struct Rates {
    double omega, gamma;
    std::size_t row;
  };
  std::vector<Rates> rates(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const RowBound& r = rows[i];
    const double w2 =
        scale.strutStiffness * r.strutStiffness + scale.hingeStiffness * r.hingeStiffness + scale.gasStiffness * r.gasStiffness;
    const double gamma = scale.strutDamping * r.strutDamping + scale.hingeDamping * r.hingeDamping + r.drag;
    rates[i] = {std::sqrt(w2), gamma, i};
    out.omegaMax = std::max(out.omegaMax, rates[i].omega);
    out.gammaMax = std::max(out.gammaMax, gamma);
  }
  // A row dominated by another in both rates cannot limit the step, so only the rows on the
  // front (no other row both stiffer and more damped) are solved for their critical step: a
  // handful instead of every vertex (suggest on 1000 bodies took longer than running them).
  // Among equal rates the lowest row comes first and alone stays, as in a scan of every row.
  std::sort(rates.begin(), rates.end(), [](const Rates& a, const Rates& b) {
    if (a.omega != b.omega) return a.omega > b.omega;
    if (a.gamma != b.gamma) return a.gamma > b.gamma;
    return a.row < b.row;
  });
  double frontGamma = -1.0;
  std::size_t bestRow = rows.size();
  for (const Rates& r : rates) {
    if (!(r.gamma > frontGamma)) continue;
    frontGamma = r.gamma;
    const double h = criticalStep(integrator, r.omega, r.gamma, horizon);
    if (h < out.dtMax || (h == out.dtMax && r.row < bestRow)) {
      out.dtMax = h;
      bestRow = r.row;
      out.vertex = rows[r.row].vertex;
    }
  }
  return out;
}

StabilityReport estimateStability(const Model& model, const std::vector<Vec3>& x, Integrator integrator,
                                  double horizon) {
  StabilityReport report;
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    BodyStability s = bodyStability(gershgorinRows(model, x.data(), b), integrator, horizon);
    s.body = b;
    if (s.dtMax < report.dtMax) {
      report.dtMax = s.dtMax;
      report.limitingBody = b;
    }
    report.bodies.push_back(s);
  }
  return report;
}

int safeSubsteps(double dt, double dtMax, double safety) {
  if (!(dtMax > 0.0) || !std::isfinite(dtMax)) return 1;
  const double n = std::ceil(dt / (safety * dtMax));
  return n < 1.0 ? 1 : (n > 1e6 ? 1000000 : static_cast<int>(n));
}

RunOutcome runMonitored(const Model& model, Integrator integrator, double dt, double horizon,
                        const std::vector<Vec3>* initialPositions) {
  World world(model, integrator, dt);
  if (initialPositions) world.setState(*initialPositions, world.velocities());
  // Stability, not accuracy: energy may wander (a symplectic method's energy error is O(dt)),
  // but never rise by more than its own scale.
  MonitorLimits limits;
  limits.energyTolerance = 1.0;
  limits.energyFromLowest = false;
  Monitor monitor(world, limits);
  RunOutcome out;
  const auto steps = static_cast<uint64_t>(std::llround(horizon / dt));
  const uint64_t every = std::max<uint64_t>(1, std::min<uint64_t>(20, steps / 50));
  for (uint64_t s = 1; s <= steps; ++s) {
    world.step();
    if (s % every != 0 && s != steps) continue;
    if (const auto failure = monitor.check(world)) {
      out.stable = false;
      out.failure = failure->message;
      out.step = failure->step;
      const std::string& m = failure->message;
      out.kind = m.find("NaN") != std::string::npos         ? "nan"
                 : m.find("blew up") != std::string::npos   ? "blow-up"
                 : m.find("energy") != std::string::npos    ? "energy"
                 : m.find("behind a plane") != std::string::npos ? "penetration"
                 : m.find("volume") != std::string::npos    ? "volume"
                                                                 : "other";
      break;
    }
  }
  for (const Vec3& p : world.positions()) out.finiteAtEnd = out.finiteAtEnd && isFinite(p);
  for (const Vec3& v : world.velocities()) out.finiteAtEnd = out.finiteAtEnd && isFinite(v);
  return out;
}

MeasuredStep largestStableStep(const Model& model, Integrator integrator, double horizon, double guess, double maxDt,
                               const std::vector<Vec3>* initialPositions, int iterations) {
  MeasuredStep out;
  auto run = [&](double dt) { return runMonitored(model, integrator, dt, horizon, initialPositions); };
  double hi = std::min(guess * 4.0, maxDt);
  RunOutcome atHi = run(hi);
  while (atHi.stable) {
    if (hi >= maxDt) {
      out.dt = maxDt;
      out.capped = true;
      return out;
    }
    hi = std::min(hi * 4.0, maxDt);
    atHi = run(hi);
  }
  double lo = hi / 4.0;
  for (RunOutcome atLo = run(lo); !atLo.stable; atLo = run(lo)) {
    hi = lo;
    atHi = std::move(atLo);
    lo /= 4.0;
    if (lo < 1e-9) {
      out.dt = 0.0;
      out.above = std::move(atHi);
      return out;
    }
  }
  out.above = std::move(atHi);
  for (int i = 0; i < iterations; ++i) {
    const double mid = std::sqrt(lo * hi);
    RunOutcome r = run(mid);
    if (r.stable) {
      lo = mid;
    } else {
      hi = mid;
      out.above = std::move(r);
    }
  }
  out.dt = lo;
  return out;
}

namespace {

BodyInfo singleBody(const std::string& name, const Model& model) {
  BodyInfo info;
  info.name = name;
  info.vertexCount = static_cast<uint32_t>(model.mass.size());
  info.strutCount = static_cast<uint32_t>(model.struts.size());
  info.hingeCount = static_cast<uint32_t>(model.hinges.size());
  info.faceCount = static_cast<uint32_t>(model.faces.size());
  for (double m : model.mass) info.mass += m;
  info.restSize = length(boundsOf(model.restPosition).size());
  return info;
}

std::vector<Vec3> wings(double angle) {
  const double a = angle / 2;
  return {{0, 0, 0}, {1, 0, 0}, {0.4, std::cos(a), -std::sin(a)}, {0.6, -std::cos(a), -std::sin(a)}};
}

// A ball (icosphere, 42 vertices, radius 1, mass 1) with the given parameters.
BodyDesc ball(double strutPeriod, double strutDecay, double hingePeriod, double hingeDecay) {
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = makeIcosphere(1.0, 1);
  desc.mass = 1.0;
  desc.strutPeriod = strutPeriod;
  desc.hingePeriod = hingePeriod;
  if (strutDecay > 0) desc.strutDecay = strutDecay;
  else desc.strutDamping = 0.0;
  if (hingeDecay > 0) desc.hingeDecay = hingeDecay;
  else desc.hingeDamping = 0.0;
  return desc;
}

StabilityCase fromBody(const std::string& name, const std::string& description, const BodyDesc& desc,
                       Vec3 gravity = {}) {
  StabilityCase c;
  c.name = name;
  c.description = description;
  c.model.gravity = gravity;
  addBody(c.model, desc);
  c.positions = c.model.restPosition;
  return c;
}

}  // namespace

StabilityCase strutCase(double period, double decay) {
  StabilityCase c;
  c.name = "strut";
  Model& m = c.model;
  m.gravity = {};
  m.mass = {1, 1};
  m.invMass = {1, 1};
  m.restPosition = {{0, 0, 0}, {1, 0, 0}};
  m.initialVelocity = {{}, {}};
  m.body = {0, 0};
  const double mean = 1.0;
  m.struts = {{0, 1, 1.0, stiffnessFromPeriod(mean, period), decay > 0 ? dampingFromDecay(mean, decay) : 0.0}};
  m.bodies = {singleBody("strut", m)};
  c.positions = {{0, 0, 0}, {1.1, 0, 0}};
  return c;
}

StabilityCase hingeCase(double period, double decay, double restAngle, double startAngle) {
  StabilityCase c;
  c.name = "hinge";
  Model& m = c.model;
  m.gravity = {};
  m.mass = {1, 1, 1, 1};
  m.invMass = {1, 1, 1, 1};
  m.restPosition = wings(restAngle);
  m.initialVelocity = std::vector<Vec3>(4);
  m.body = {0, 0, 0, 0};
  m.faces = {{0, 1, 2}, {1, 0, 3}};
  HingeGeometry g;
  hingeGeometry(m.restPosition[0], m.restPosition[1], m.restPosition[2], m.restPosition[3], g);
  const double r = 0.5 * (g.leverLeft + g.leverRight);
  Hinge h{{0, 1, 2, 3}, g.theta, torsionStiffnessFromPeriod(1.0, r, period),
          decay > 0 ? torsionDampingFromDecay(1.0, r, decay) : 0.0, {0.2 * g.leverLeft, 0.2 * g.leverRight}};
  m.hinges = {h};
  // Struts of twice the hinge's period hold the triangles' shape (softer struts would let the
  // hinge crush its own faces).
  for (auto [i, j] : {std::pair<uint32_t, uint32_t>{0, 1}, {0, 2}, {1, 2}, {0, 3}, {1, 3}}) {
    const auto& p = m.restPosition;
    m.struts.push_back({i, j, length(p[j] - p[i]), stiffnessFromPeriod(1.0, 2 * period),
                        decay > 0 ? dampingFromDecay(1.0, decay) : 0.0});
  }
  m.bodies = {singleBody("hinge", m)};
  c.positions = wings(startAngle);
  return c;
}

std::vector<CaseFactory> stabilityCases() {
  std::vector<CaseFactory> cases;
  auto add = [&](std::string name, bool degenerate, bool stiff, std::function<StabilityCase()> make) {
    cases.push_back({std::move(name), degenerate, stiff, std::move(make)});
  };
  add("stiff strut", false, false, [] {
    StabilityCase c = strutCase(0.001, 0.1);
    c.name = "stiff strut";
    c.description = "two masses, one strut, P = 1 ms, T = 0.1 s";
    return c;
  });
  add("stiff hinge", false, false, [] {
    StabilityCase c = hingeCase(0.001, 0.1);
    c.name = "stiff hinge";
    c.description = "two triangles, one hinge, P_theta = 1 ms, T_theta = 0.1 s, released bent";
    return c;
  });
  add("stiff ball", false, true, [] {
    StabilityCase c = fromBody("stiff ball", "icosphere, P = P_theta = 1 ms, released squashed to 0.7",
                               ball(0.001, 0.1, 0.001, 0.1));
    for (Vec3& p : c.positions) p.y *= 0.7;
    return c;
  });
  add("stiff gas", false, true, [] {
    // The gas is the stiff term, and it stiffens as the volume falls (p V = const).
    BodyDesc desc = ball(0.05, 0.1, 0.0, 0.0);
    desc.volumePeriod = 0.0002;
    StabilityCase c = fromBody("stiff gas", "icosphere, P = 50 ms, no hinges, gas P_V = 0.2 ms, released squashed to 0.7",
                               desc);
    for (Vec3& p : c.positions) p.y *= 0.7;
    return c;
  });
  add("overdamped", false, true, [] {
    StabilityCase c = fromBody("overdamped", "icosphere, P = 50 ms, T = 0.1 ms (T << P: damping is the stiff term)",
                               ball(0.05, 1e-4, 0.5, 2.0));
    for (Vec3& p : c.positions) p.y *= 0.7;
    return c;
  });
  add("undamped", false, false, [] {
    StabilityCase c = fromBody("undamped", "icosphere, P = 50 ms, P_theta = 0.5 s, no damping at all",
                               ball(0.05, 0.0, 0.5, 0.0));
    for (Vec3& p : c.positions) p.y *= 0.7;
    return c;
  });
  add("mass ratio 1:1e4", false, true, [] {
    // Tiny triangles beside large ones: a cube whose corner vertices are pulled almost onto
    // their neighbours would do it geometrically; the masses are what matter for stability,
    // so every other vertex of the ball gets 1e-4 of its mass (springs keep their constants).
    StabilityCase c = fromBody("mass ratio 1:1e4", "icosphere, P = 50 ms, every other vertex 1e-4 times lighter",
                               ball(0.05, 0.03, 0.5, 2.0));
    for (std::size_t i = 0; i < c.model.mass.size(); i += 2) {
      c.model.mass[i] *= 1e-4;
      c.model.invMass[i] = 1.0 / c.model.mass[i];
    }
    for (Vec3& p : c.positions) p.y *= 0.9;
    return c;
  });
  add("sliver", false, false, [] {
    // A tetrahedron whose apex is pushed down to 1 % of its height: four sliver faces.
    BodyDesc desc = ball(0.05, 0.03, 0.5, 2.0);
    desc.name = "sliver";
    desc.mesh = makeTetrahedron(1.0);
    const Vec3 base = (desc.mesh.positions[0] + desc.mesh.positions[1] + desc.mesh.positions[2]) / 3.0;
    Vec3& apex = desc.mesh.positions[3];
    apex = base + (apex - base) * 0.01;
    StabilityCase c = fromBody("sliver", "tetrahedron flattened to 1 % of its height (hinge levers 1 % of edge)", desc);
    Vec3& lifted = c.positions[c.model.bodies[0].modelVertex[3]];  // the apex, in model numbering
    lifted = lifted + (lifted - base) * 0.5;
    return c;
  });
  add("degenerate sliver", true, false, [] {
    BodyDesc desc = ball(0.05, 0.03, 0.5, 2.0);
    desc.name = "degenerate";
    desc.mesh = makeTetrahedron(1.0);
    // Apex on the base plane's edge line: a hinge with |r| = 0 and a zero-area face.
    desc.mesh.positions[3] = (desc.mesh.positions[0] + desc.mesh.positions[1]) * 0.5;
    return fromBody("degenerate sliver", "tetrahedron with its apex on an edge (|r| = 0): refused at load", desc);
  });
  add("flat hinge", false, false, [] {
    StabilityCase c = hingeCase(0.01, 0.1, 1e-6, 0.3);
    c.name = "flat hinge";
    c.description = "hinge with theta0 = 1e-6 (flat), P_theta = 10 ms, released at 0.3 rad";
    return c;
  });
  add("folded hinge", false, false, [] {
    StabilityCase c = hingeCase(0.01, 0.1, 3.1, -3.0);
    c.name = "folded hinge";
    c.description = "hinge with theta0 = 3.1 rad, released at -3.0 (through +-pi, where the angle wraps)";
    return c;
  });
  add("squashed", false, false, [] {
    StabilityCase c = fromBody("squashed", "icosphere (P = 50 ms) squashed to a tenth of its height at t = 0",
                               ball(0.05, 0.03, 0.5, 2.0));
    for (Vec3& p : c.positions) p.y *= 0.1;
    return c;
  });
  add("impact", false, false, [] {
    // Ten times the free-fall speed from 1 m (44 m/s) onto a thin triangle plate. The ball is
    // stiffer than the others (P = 20 ms, P_theta = 0.2 s) so that it physically survives the
    // impact: with P = 50 ms it turns inside out at any step (measured with RK4 at 20 us), and
    // the case would measure the physics, not the integrators.
    BodyDesc desc = ball(0.02, 0.03, 0.2, 2.0);
    desc.velocity = {0, -10.0 * std::sqrt(2 * 9.81 * 1.0), 0};
    for (Vec3& p : desc.mesh.positions) p.y += 1.5;
    StabilityCase c = fromBody("impact", "icosphere at 10x free-fall speed (44 m/s) onto a thin triangle", desc,
                               {0, -9.81, 0});
    TriangleCollider plate;
    plate.name = "plate";
    plate.mesh.positions = {{-3, 0, -3}, {3, 0, -3}, {0, 0, 4}};
    plate.mesh.triangles = {{0, 2, 1}};
    plate.buildBvh();
    c.model.colliders.meshes.push_back(plate);
    c.model.colliders.restingSpeed = 0.1;
    c.model.initialVelocity = std::vector<Vec3>(c.model.mass.size(), desc.velocity);
    return c;
  });
  add("gravity 100 g", false, false, [] {
    // Stiffened as the impact case (P = 20 ms, P_theta = 0.2 s): with P = 50 ms the ball, hitting
    // at 31 m/s, physically squashes to 9% of its volume (RK4 at 20 us) and backward Euler's
    // flattening to 0% or just above was decided by rounding.
    BodyDesc desc = ball(0.02, 0.03, 0.2, 2.0);
    for (Vec3& p : desc.mesh.positions) p.y += 1.5;
    StabilityCase c = fromBody("gravity 100 g", "icosphere dropped from 0.5 m onto the ground under 981 m/s^2", desc,
                               {0, -981.0, 0});
    c.model.colliders.planes.push_back({{0, 0, 0}, {0, 1, 0}, {}});
    c.model.colliders.restingSpeed = 4.0 * 981.0 * 1e-3;
    return c;
  });
  return cases;
}

}  // namespace springy

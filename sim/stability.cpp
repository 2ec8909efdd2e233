#include "sim/stability.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "sim/hinge.h"
#include "sim/monitor.h"

namespace springy {
namespace {

struct ModeState {
  double x, v;
};

// One step of each integrator on the scalar mode, mirroring World::step.
ModeState stepMode(Integrator integrator, double w2, double g, double h, ModeState s) {
  auto a = [&](double x, double v) { return -w2 * x - g * v; };
  switch (integrator) {
    case Integrator::ExplicitEuler: return {s.x + h * s.v, s.v + h * a(s.x, s.v)};
    case Integrator::SymplecticEuler: {
      const double v = s.v + h * a(s.x, s.v);
      return {s.x + h * v, v};
    }
    case Integrator::VelocityVerlet:
    case Integrator::AdaptiveVerlet:
      break;  // it keeps its acceleration between steps: three states, verletAmplification
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
    case Integrator::BogackiShampine: {  // its third-order solution
      const double k1x = s.v, k1v = a(s.x, s.v);
      const double k2x = s.v + 0.5 * h * k1v, k2v = a(s.x + 0.5 * h * k1x, s.v + 0.5 * h * k1v);
      const double k3x = s.v + 0.75 * h * k2v, k3v = a(s.x + 0.75 * h * k2x, s.v + 0.75 * h * k2v);
      return {s.x + h * (2.0 / 9 * k1x + 1.0 / 3 * k2x + 4.0 / 9 * k3x),
              s.v + h * (2.0 / 9 * k1v + 1.0 / 3 * k2v + 4.0 / 9 * k3v)};
    }
    case Integrator::BackwardEuler:
    case Integrator::Vbd: {  // converged, vertex block descent is backward Euler
      // (1 + h g + h^2 w2) v1 = v - h w2 x ; x1 = x + h v1
      const double v = (s.v - h * w2 * s.x) / (1 + h * g + h * h * w2);
      return {s.x + h * v, v};
    }
  }
  return s;
}

// Stable: the mode's energy grows at most 2x over the horizon. Symplectic Euler's also swings
// within a bounded orbit, even undamped and below 2/omega: released from rest, a mode's energy (at
// one instant, World::synchronizedState; velocity Verlet's state, whose orbit starts at the
// half-step kick h a/2 rather than at rest) reaches 1/(1 - (omega h)^2/4) times its start, which
// is 2 at omega h = sqrt 2 (the stiff strut and hinges of docs/stability.md fail the energy check
// there, at 0.71-0.77 of 2/omega). Velocity Verlet and leapfrog released from rest stay at or
// below their start.
bool stableAt(Integrator integrator, double omega, double gamma, double h, double horizon) {
  const double rho = amplification(integrator, omega, gamma, h);
  if (!std::isfinite(rho)) return false;
  double swing = 1.0;
  if (integrator == Integrator::SymplecticEuler) {
    const double q = 0.25 * omega * omega * h * h;
    if (q >= 1.0) return false;
    swing = 1.0 / (1.0 - q);
  }
  const double growth = rho <= 1.0 ? 0.0 : std::log(rho) * std::max(1.0, horizon / h);
  return growth + 0.5 * std::log(swing) <= 0.5 * std::log(2.0);
}

// Velocity Verlet as World runs it: the acceleration at the step's end, evaluated at the
// predicted velocity v + h a, is kept as the next step's a (sim/world.cpp). The state is then
// (x, v, a), and on a damped mode that halves the stable step (pure damping: h < 1/gamma against
// 2/gamma when a is evaluated afresh); undamped, the kept a is exact and the limit stays 2/omega.
// In the dimensionless state (x, h v, h^2 a), with W = omega^2 h^2 and G = gamma h, the map is
//   [[1, 1, 1/2], [-W/2, 1 - W/2 - G/2, 1/2 - W/4 - G/2], [-W, -W - G, -W/2 - G]];
// its spectral radius from the characteristic polynomial: the cubic's real root, then the
// quadratic left (whose complex pair has |l|^2 = its constant term, free of cancellation).
double verletAmplification(double w2, double g, double h) {
  const double W = w2 * h * h, G = g * h;
  const double m[3][3] = {{1.0, 1.0, 0.5},
                          {-0.5 * W, 1.0 - 0.5 * W - 0.5 * G, 0.5 - 0.25 * W - 0.5 * G},
                          {-W, -W - G, -0.5 * W - G}};
  const double t = m[0][0] + m[1][1] + m[2][2];
  const double minors = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) + (m[0][0] * m[2][2] - m[0][2] * m[2][0]) +
                        (m[1][1] * m[2][2] - m[1][2] * m[2][1]);
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  // l^3 - t l^2 + minors l - det = 0; with l = y + t/3: y^3 + p y + q = 0.
  const double p = minors - t * t / 3.0, q = -2.0 * t * t * t / 27.0 + t * minors / 3.0 - det;
  const double disc = 0.25 * q * q + p * p * p / 27.0;
  double rho;
  if (disc > 0.0) {  // one real root and a complex pair (or a double real pair)
    const double s = std::sqrt(disc);
    const double root = std::cbrt(-0.5 * q + s) + std::cbrt(-0.5 * q - s) + t / 3.0;
    const double b = t - root, c = minors - root * b;  // l^2 - b l + c
    const double d2 = 0.25 * b * b - c;
    const double pair = d2 < 0.0 ? std::sqrt(std::max(c, 0.0))
                                 : std::max(std::fabs(0.5 * b + std::sqrt(d2)), std::fabs(0.5 * b - std::sqrt(d2)));
    rho = std::max(std::fabs(root), pair);
  } else {  // three real roots
    const double r = std::sqrt(-p / 3.0);
    const double phi = std::acos(std::clamp(-0.5 * q / (r * r * r), -1.0, 1.0));
    rho = 0.0;
    for (int k = 0; k < 3; ++k) {
      rho = std::max(rho, std::fabs(2.0 * r * std::cos((phi - 2.0 * M_PI * k) / 3.0) + t / 3.0));
    }
  }
  // Far below the limit two roots sit near 1 and their round-off can read as growth of about
  // 1e-16 / (omega h); a true instability is orders larger.
  return rho <= 1.0 + 1e-9 ? std::min(rho, 1.0) : rho;
}

}  // namespace

double amplification(Integrator integrator, double omega, double gamma, double h) {
  const double w2 = omega * omega;
  if (integrator == Integrator::VelocityVerlet || integrator == Integrator::AdaptiveVerlet) {
    return verletAmplification(w2, gamma, h);
  }
  const ModeState c0 = stepMode(integrator, w2, gamma, h, {1, 0});
  const ModeState c1 = stepMode(integrator, w2, gamma, h, {0, 1});
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
  if (isImplicit(integrator) || !(rate > 0.0)) return std::numeric_limits<double>::infinity();
  // Scan upward from a surely stable step for the first unstable one, then bisect. Every method
  // but explicit Euler is stable on the mode far below 1 / rate; explicit Euler's limit from the
  // horizon can be far smaller.
  double lo = (integrator == Integrator::ExplicitEuler ? 1e-6 : 1e-3) / rate;
  if (!stableAt(integrator, omega, gamma, lo, horizon)) return lo;
  double hi = lo;
  if (integrator != Integrator::ExplicitEuler) {
    // The scan's 24th step (0.21 / rate), stable for every one of them, where the scan goes on:
    // the same steps, bit for bit, and a third fewer tests (these bounds are updated every few
    // steps of an adaptive run).
    double skip = hi;
    for (int k = 0; k < 24; ++k) skip *= 1.25;
    if (stableAt(integrator, omega, gamma, skip, horizon)) hi = skip;
  }
  for (;;) {
    lo = hi;
    hi *= 1.25;
    if (hi > 1e4 / rate) return std::numeric_limits<double>::infinity();
    if (!stableAt(integrator, omega, gamma, hi, horizon)) break;
  }
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (lo + hi);
    (stableAt(integrator, omega, gamma, mid, horizon) ? lo : hi) = mid;
  }
  return lo;
}

std::vector<RowBound> gershgorinRows(const Model& model, const Vec3* x, uint32_t body, const double* invMass) {
  if (!invMass) invMass = model.invMass.data();
  const BodyInfo& info = model.bodies[body];
  const std::vector<ForceStage> stages = stagesOf(model);
  std::vector<RowBound> rows(info.vertexCount);
  for (uint32_t k = 0; k < info.vertexCount; ++k) {
    rows[k].vertex = info.firstVertex + k;
    // The kinds' -c m_i on the diagonal (the deformation damping's rigid part only lowers the bound).
    rows[k].drag = diagonalDamping(model, stages, info.firstVertex + k);
  }
  // Each kind's rates, in the registry's order (sim/force_kinds.h boundRows).
  for (ForceStage stage : stages) {
    if (const auto bound = forceKind(stage).boundRows) bound(model, x, invMass, body, rows.data());
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
    const double w2 = scale.strutStiffness * r.strutStiffness + scale.hingeStiffness * r.hingeStiffness +
                      scale.gasStiffness * r.gasStiffness + r.otherStiffness;
    const double gamma = scale.strutDamping * r.strutDamping + scale.hingeDamping * r.hingeDamping + r.drag + r.otherDamping;
    rates[i] = {std::sqrt(w2), gamma, i};
    out.omegaMax = std::max(out.omegaMax, rates[i].omega);
    out.gammaMax = std::max(out.gammaMax, gamma);
  }
  // A row dominated by another in both rates cannot limit the step, so only the rows on the
  // front (no other row both stiffer and more damped) are solved for their critical step: a
  // handful instead of every vertex (suggest on 1000 bodies took longer than running them).
  // Among equal rates the lowest row comes first and alone stays, as in a scan of every row.
  // The front starts at the first row in that order; only rows more damped than it can follow,
  // so only they are sorted (often none: the stiffest row is also the most damped; a sort of
  // every row was a tenth of an adaptive run, which updates these bounds every 4 steps).
  const auto before = [](const Rates& a, const Rates& b) {
    if (a.omega != b.omega) return a.omega > b.omega;
    if (a.gamma != b.gamma) return a.gamma > b.gamma;
    return a.row < b.row;
  };
  if (rates.empty()) return out;
  std::swap(rates.front(), *std::min_element(rates.begin(), rates.end(), before));
  const double firstGamma = rates.front().gamma;
  const auto tail =
      std::partition(rates.begin() + 1, rates.end(), [&](const Rates& r) { return r.gamma > firstGamma; });
  std::sort(rates.begin() + 1, tail, before);
  rates.erase(tail, rates.end());
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

Integrator contactLimitedIntegrator(const Model& model, uint32_t body, Integrator integrator) {
  if (!isImplicit(integrator)) return integrator;
  // Between bodies or within one. A single body's edges against triangle colliders' edges take
  // the contact stage too (BodyContacts::needed), but only at a collider's rims: the impact case
  // (a ball onto a plate) runs backward Euler at 0.1 s.
  const auto taking =
      std::count_if(model.bodies.begin(), model.bodies.end(), [](const BodyInfo& b) { return b.contact; });
  const auto actsOn = [&](const BodyInfo& b) { return b.selfContact || (b.contact && taking >= 2); };
  const bool acts =
      body == kAnyBody ? std::any_of(model.bodies.begin(), model.bodies.end(), actsOn) : actsOn(model.bodies[body]);
  return acts ? Integrator::SymplecticEuler : integrator;
}

StabilityReport estimateStability(const Model& model, const std::vector<Vec3>& x, Integrator integrator,
                                  double horizon, const double* invMass) {
  StabilityReport report;
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    BodyStability s =
        bodyStability(gershgorinRows(model, x.data(), b, invMass), contactLimitedIntegrator(model, b, integrator), horizon);
    s.body = b;
    if (s.dtMax < report.dtMax) {
      report.dtMax = s.dtMax;
      report.limitingBody = b;
    }
    report.bodies.push_back(s);
  }
  return report;
}

ModeEstimator::ModeEstimator(const Forces& forces) : forces_(forces) {
  const Model& model = forces.model();
  const std::size_t n = model.invMass.size();
  invSqrtMass_.resize(n);
  stiff_.resize(n);
  damped_.resize(n);
  plus_.resize(n);
  minus_.resize(n);
  fPlus_.resize(n);
  fMinus_.resize(n);
  zero_.assign(n, Vec3{0, 0, 0});
  double size = 0.0;
  for (const BodyInfo& b : model.bodies) size = std::max(size, b.restSize);
  epsilon_ = 1e-7 * (size > 0.0 ? size : 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    invSqrtMass_[i] = std::sqrt(model.invMass[i]);  // 0 for a pinned vertex: it never moves
    // A start with a part along every mode (a fixed pseudo-random vector: deterministic).
    const double k = static_cast<double>(i);
    stiff_[i] = Vec3{std::sin(1.0 + 0.7 * k), std::cos(2.0 + 1.3 * k), std::sin(3.0 + 0.31 * k)} * invSqrtMass_[i];
    damped_[i] = stiff_[i];
  }
}

namespace {

double dotAll(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += dot(a[i], b[i]);
  return sum;
}

}  // namespace

void ModeEstimator::product(const std::vector<Vec3>& x, bool damping, const std::vector<Vec3>& u,
                            std::vector<Vec3>& y) {
  // y = M^-1/2 A M^-1/2 u with A = -df/dx (or -df/dv), as a central difference whose largest
  // vertex displacement (or velocity) is epsilon.
  const std::size_t n = u.size();
  double largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) largest = std::max(largest, length(u[i]) * invSqrtMass_[i]);
  y.resize(n);
  if (!(largest > 0.0)) {
    std::fill(y.begin(), y.end(), Vec3{0, 0, 0});
    return;
  }
  const double e = epsilon_ / largest;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = u[i] * (invSqrtMass_[i] * e);
    if (damping) {
      plus_[i] = d;
      minus_[i] = d * -1.0;
    } else {
      plus_[i] = x[i] + d;
      minus_[i] = x[i] - d;
    }
  }
  if (damping) {
    forces_.evaluate(x.data(), plus_.data(), 0.0, fPlus_.data());
    forces_.evaluate(x.data(), minus_.data(), 0.0, fMinus_.data());
  } else {
    forces_.evaluate(plus_.data(), zero_.data(), 0.0, fPlus_.data());
    forces_.evaluate(minus_.data(), zero_.data(), 0.0, fMinus_.data());
  }
  for (std::size_t i = 0; i < n; ++i) y[i] = (fMinus_[i] - fPlus_[i]) * (invSqrtMass_[i] / (2.0 * e));
}

namespace {

// Scales u to unit length; false if it is zero (every vertex pinned) or not finite.
bool normalise(std::vector<Vec3>& u) {
  const double sum = dotAll(u, u);
  if (!(sum > 0.0) || !std::isfinite(sum)) return false;
  const double scale = 1.0 / std::sqrt(sum);
  for (Vec3& p : u) p = p * scale;
  return true;
}

}  // namespace

double ModeEstimator::iterate(const std::vector<Vec3>& x, bool damping, std::vector<Vec3>& u, int iterations) {
  // Power iteration: the damping matrix is positive semi-definite, so its largest eigenvalue is
  // also its largest in magnitude, which the iteration finds.
  if (!normalise(u)) return 0.0;
  double lambda = 0.0;
  for (int it = 0; it < iterations; ++it) {
    product(x, damping, u, y_);
    lambda = dotAll(u, y_);
    u.swap(y_);
    if (!normalise(u)) return std::isfinite(lambda) ? 0.0 : std::numeric_limits<double>::infinity();
  }
  return std::isfinite(lambda) ? std::max(lambda, 0.0) : std::numeric_limits<double>::infinity();
}

double ModeEstimator::lanczos(const std::vector<Vec3>& x, std::vector<Vec3>& u, int steps) {
  // The stiffness matrix is indefinite where a body is compressed: a strut shorter than its rest
  // length pulls its ends sideways (its geometric stiffness is negative), and a strut at a third
  // of its rest length has a sideways eigenvalue twice its axial one in magnitude. Power
  // iteration then converges to that negative end and missed the positive one (in bunny_light's
  // landings its estimates swung between 3,000 and 17,000 rad/s from one frame to the next, and
  // its too-long steps let the energy rise). Lanczos (Golub & Van Loan, Matrix Computations,
  // 4th ed., section 10.1) finds both ends of the spectrum from the same products: the largest
  // eigenvalue of the tridiagonal matrix of k steps is the largest Rayleigh quotient over the
  // Krylov space, never below the power iteration's k-th. Fully reorthogonalised (k is small).
  if (!normalise(u)) return 0.0;
  const std::size_t n = u.size();
  if (basis_.size() < static_cast<std::size_t>(steps)) basis_.resize(static_cast<std::size_t>(steps));
  alpha_.clear();  // members: no allocation after the first call
  beta_.clear();
  basis_[0] = u;
  int m = 0;
  for (int j = 0; j < steps; ++j) {
    const std::vector<Vec3>& q = basis_[static_cast<std::size_t>(j)];
    product(x, false, q, y_);
    const double a = dotAll(q, y_);
    if (!std::isfinite(a)) return std::numeric_limits<double>::infinity();
    alpha_.push_back(a);
    m = j + 1;
    for (int pass = 0; pass < 2; ++pass) {  // Gram-Schmidt twice against every basis vector
      for (int i = 0; i <= j; ++i) {
        const std::vector<Vec3>& v = basis_[static_cast<std::size_t>(i)];
        const double c = dotAll(v, y_);
        for (std::size_t k = 0; k < n; ++k) y_[k] -= v[k] * c;
      }
    }
    const double b = std::sqrt(dotAll(y_, y_));
    if (j + 1 == steps || !(b > 1e-12 * std::max(std::fabs(a), 1e-300))) break;  // or an invariant subspace
    beta_.push_back(b);
    std::vector<Vec3>& next = basis_[static_cast<std::size_t>(j + 1)];
    next.resize(n);
    for (std::size_t k = 0; k < n; ++k) next[k] = y_[k] * (1.0 / b);
  }
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(m, m);
  for (int i = 0; i < m; ++i) {
    t(i, i) = alpha_[static_cast<std::size_t>(i)];
    if (i + 1 < m) t(i, i + 1) = t(i + 1, i) = beta_[static_cast<std::size_t>(i)];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(t);
  if (solver.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const double theta = solver.eigenvalues()(m - 1);  // ascending
  // The next call starts from this mode's Ritz vector.
  const Eigen::VectorXd s = solver.eigenvectors().col(m - 1);
  std::fill(u.begin(), u.end(), Vec3{0, 0, 0});
  for (int i = 0; i < m; ++i) {
    const std::vector<Vec3>& v = basis_[static_cast<std::size_t>(i)];
    for (std::size_t k = 0; k < n; ++k) u[k] += v[k] * s(i);
  }
  return std::isfinite(theta) ? std::max(theta, 0.0) : std::numeric_limits<double>::infinity();
}

ModeEstimator::Rates ModeEstimator::estimate(const std::vector<Vec3>& x, int iterations) {
  Rates r;
  r.omega = std::sqrt(lanczos(x, stiff_, iterations));
  r.gamma = iterate(x, true, damped_, iterations);
  probe_ = stiff_;
  r.stiffGamma = std::min(r.gamma, iterate(x, true, probe_, 1));  // one product: a Rayleigh quotient
  // The vertex with the largest share of a mode, among [begin, end).
  const auto largest = [](const std::vector<Vec3>& u, uint32_t begin, uint32_t end) {
    uint32_t best = begin;
    for (uint32_t i = begin + 1; i < end; ++i) {
      if (lengthSquared(u[i]) > lengthSquared(u[best])) best = i;
    }
    return best;
  };
  // The body with the largest share of the stiff mode, and its vertex with the largest.
  const Model& model = forces_.model();
  double best = -1.0;
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    double share = 0.0;
    for (uint32_t k = 0; k < model.bodies[b].vertexCount; ++k) {
      const Vec3& p = stiff_[model.bodies[b].firstVertex + k];
      share += dot(p, p);
    }
    if (share > best) best = share, r.body = b;
  }
  if (!model.bodies.empty()) {
    const BodyInfo& info = model.bodies[r.body];
    r.stiffVertex = largest(stiff_, info.firstVertex, info.firstVertex + info.vertexCount);
  }
  r.dampedVertex = largest(damped_, 0, static_cast<uint32_t>(damped_.size()));
  return r;
}

double ModeEstimator::step(Integrator integrator, const Rates& rates, double horizon, Limit* limit) {
  constexpr double kShortfall = 1.05;
  const double omega = kShortfall * rates.omega, gamma = kShortfall * rates.gamma;
  // A mode as damped with no stiffness (the two rates need not belong to one mode).
  const double damped = criticalStep(integrator, 0.0, gamma, horizon);
  double stiff, withDamping;
  if (integrator == Integrator::ExplicitEuler) {
    // Explicit Euler amplifies every undamped mode at any step: only the damping keeps it
    // stable, so the stiff mode is taken with its own damping (lowered by the margin, the safe
    // side here).
    stiff = withDamping = criticalStep(integrator, omega, rates.stiffGamma / kShortfall, horizon);
  } else {
    stiff = criticalStep(integrator, omega, 0.0, horizon);
    withDamping = criticalStep(integrator, omega, gamma, horizon);
  }
  const double h = std::min({stiff, withDamping, damped});
  if (limit != nullptr) *limit = std::min(withDamping, damped) < stiff ? Limit::Damping : Limit::Stiffness;
  return h;
}

StabilitySurvey surveyStability(const Model& model, Integrator integrator, double duration, double frame,
                                double interval, double tolerance, unsigned threads,
                                const std::vector<Vec3>* initial, double landingTolerance) {
  constexpr int kFirstIterations = 60, kIterations = 12;
  constexpr double kNearest = 1.5;  // where Gershgorin's limit is within this of its smallest
  // Never finer than a 64th of a frame: a scene with a tiny dt would otherwise spend the survey
  // on Gershgorin's bound.
  interval = std::min(frame, std::max(interval, frame / 64));
  StabilitySurvey survey;
  World world(model, kDefaultAdaptive, interval);
  world.setTolerance(tolerance);
  world.setThreads(threads);
  if (initial != nullptr) world.setState(*initial, world.velocities());
  Monitor monitor(world);
  ModeEstimator modes(world);
  const Integrator limited = contactLimitedIntegrator(model, kAnyBody, integrator);
  const auto estimate = [&](bool always) {
    const double bound = estimateStability(model, world.positions(), integrator, duration).dtMax;
    const bool near = bound <= kNearest * survey.gershgorin;
    survey.gershgorin = std::min(survey.gershgorin, bound);
    if (!always && !near) return;
    const ModeEstimator::Rates rates =
        modes.estimate(world.positions(), survey.estimates == 0 ? kFirstIterations : kIterations);
    ModeEstimator::Limit limit{};
    const double h = ModeEstimator::step(limited, rates, duration, &limit);
    if (++survey.estimates == 1) survey.atRest = h;
    if (h < survey.dtMax) {
      const bool damping = limit == ModeEstimator::Limit::Damping;
      survey.dtMax = h;
      survey.time = world.time();
      survey.vertex = damping ? rates.dampedVertex : rates.stiffVertex;
      survey.body = damping ? model.body[survey.vertex] : rates.body;
      survey.landing = false;
      survey.limit = limit;
      survey.rate = damping ? rates.gamma : rates.omega;
      survey.position = world.positions()[survey.vertex];
    }
  };
  // At every frame: the step a landing allows (sim/monitor.h), for every method (backward Euler's
  // landings too put vertices back on their support).
  const auto landings = [&] {
    for (uint32_t b = 0; b < model.bodies.size(); ++b) {
      const double h = landingStep(world, b, landingTolerance);
      if (h < survey.dtMax) {
        survey.dtMax = h;
        survey.time = world.time();
        survey.body = b;
        survey.landing = true;
      }
    }
  };
  estimate(true);
  landings();
  const auto intervals = static_cast<long>(std::ceil(duration / interval - 1e-9));
  double nextFrame = frame;
  for (long i = 1; i <= intervals && survey.failure.empty(); ++i) {
    const double until = std::min(duration, static_cast<double>(i) * interval);
    if (!stepTo(world, until) && world.stepProblem().empty()) {
      survey.failure = "interrupted";  // the caller sees interrupted() and stops
    } else if (!world.stepProblem().empty()) {
      survey.failure = world.stepProblem();
    } else if (const auto failure = monitor.check(world)) {
      survey.failure = failure->message;
    } else {
      const bool atFrame = until >= nextFrame - 1e-9;
      if (atFrame) nextFrame += frame;
      estimate(atFrame);
      if (atFrame) landings();
    }
  }
  return survey;
}

int safeSubsteps(double dt, double dtMax, double safety) {
  if (!(dtMax > 0.0) || !std::isfinite(dtMax)) return 1;
  const double n = std::ceil(dt / (safety * dtMax));
  return n < 1.0 ? 1 : (n > 1e6 ? 1000000 : static_cast<int>(n));
}

}  // namespace springy

// springy: the stability advisor. Before running, estimate each body's highest natural
// frequency and strongest damping rate, and from them the largest stable time step of the
// chosen integrator; propose parameters for a given time step (the seed's future work, docs/model.md §15).
//
// Estimate. The stiffest mode of a body is an eigenvector of M^-1/2 K M^-1/2 (and of the
// damping matrix D likewise). Gershgorin's theorem bounds every eigenvalue by the largest row
// sum of absolute values; with 3x3 blocks, row i sums ||K_ij|| / sqrt(m_i m_j) over the
// vertices j it shares a strut or hinge with (pinned neighbours drop out: they do not move).
// A strut's block norm is k max(1, |1 - l0/l|) (its transverse stiffness when compressed), a
// hinge's k |g_i| |g_j| with g the angle's gradient at the current shape; damping likewise with
// d, plus the drag and deformation damping rates. Each row gives omega_i^2 and gamma_i; the integrator's stability on
// the test mode x'' = -omega_i^2 x - gamma_i x' bounds its step.
//
// Stability of an integrator on that mode: the spectral radius rho(h) of its one-step
// amplification matrix (computed by applying the integrator's own update to the 2x2 system;
// velocity Verlet, which keeps its end-of-step acceleration for the next step, on (x, v, a)).
// A step is stable when rho(h)^(horizon/h) <= sqrt(2), i.e. no mode more than doubles its
// energy over the run: symplectic and higher-order methods are stable below a sharp limit (2/omega for
// symplectic Euler, Verlet and leapfrog, about 2.8/omega for RK4); explicit Euler, which
// amplifies every undamped mode, gets the step at which the growth over the horizon stays
// within that tolerance (so its limit shrinks as the run gets longer). Backward Euler is unconditionally stable on
// every linear mode.
//
// Backward Euler's step is bounded still where bodies touch each other: the contact stage
// (sim/contact.h) acts after the implicit solve, on single vertices. Stopping a vertex over a
// step h stores about 1/2 k (v h)^2 in its springs while taking 1/2 m v^2 of kinetic energy, a
// gain once omega h passes about 1-2 on the mesh's stiff mode: on scenes/column.toml backward
// Euler fails at 1.0-1.8 ms (omega h 2.2 and up) and passes at 0.8-0.95 ms, where the stiffest
// mode gives symplectic Euler 0.9 ms. So a body that touches another body or itself takes
// symplectic Euler's limit under backward Euler (contactLimitedIntegrator, and
// kContactLimitReason for the messages that give it).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "sim/force_kinds.h"
#include "sim/model.h"
#include "sim/world.h"

namespace springy {

// Mass-normalised Gershgorin row sums of one vertex [1/s^2 for stiffness, 1/s for damping].
// Multipliers of a body's spring constants (P scaled by f multiplies stiffness by 1/f^2, T by f
// multiplies damping by 1/f).
struct ParameterScale {
  double strutStiffness = 1, strutDamping = 1, hingeStiffness = 1, hingeDamping = 1;
  double gasStiffness = 1;  // volume_period scaled by f: 1/f^2
};

struct BodyStability {
  uint32_t body = 0;
  double omegaMax = 0;   // bound on the highest natural frequency [rad/s]
  double gammaMax = 0;   // bound on the highest damping rate [1/s]
  double dtMax = std::numeric_limits<double>::infinity();  // largest stable step [s]
  uint32_t vertex = 0;   // the vertex whose row limits dtMax
};

struct StabilityReport {
  std::vector<BodyStability> bodies;
  double dtMax = std::numeric_limits<double>::infinity();  // over all bodies
  uint32_t limitingBody = 0;
};

// The integrator whose limit holds for `body` (any body: kAnyBody): symplectic Euler for
// backward Euler when the body touches another body or itself (above), else `integrator`.
constexpr uint32_t kAnyBody = std::numeric_limits<uint32_t>::max();
Integrator contactLimitedIntegrator(const Model& model, uint32_t body, Integrator integrator);
inline constexpr const char* kContactLimitReason =
    "the contact between bodies acts after the implicit solve, on single vertices, so the step is symplectic Euler's";

// Spectral radius of the integrator's one-step map on x'' = -omega^2 x - gamma x'.
double amplification(Integrator integrator, double omega, double gamma, double h);

// Largest h with amplification(h)^(horizon/h) <= sqrt(2) (infinity for backward Euler or a mode
// with neither stiffness nor damping).
double criticalStep(Integrator integrator, double omega, double gamma, double horizon);

// Gershgorin rows of one body at positions x, with inverse masses invMass (null: the model's; a
// run's once it released pins).
std::vector<RowBound> gershgorinRows(const Model& model, const Vec3* x, uint32_t body, const double* invMass = nullptr);

// The estimate for one body from its rows.
BodyStability bodyStability(const std::vector<RowBound>& rows, Integrator integrator, double horizon,
                            const ParameterScale& scale = {});

// The estimate for every body of a model at positions x (its state at t = 0, usually), with
// inverse masses invMass (null: the model's).
StabilityReport estimateStability(const Model& model, const std::vector<Vec3>& x, Integrator integrator,
                                  double horizon, const double* invMass = nullptr);

// The stiffest mode itself, not a bound on it: the largest eigenvalues of M^-1/2 K M^-1/2
// (omega^2; K = -df/dx at zero velocity) and of M^-1/2 D M^-1/2 (gamma; D = -df/dv), by Lanczos
// (K, indefinite in a compressed body) and power iteration (D) on products taken as central
// differences of the force stages (two force evaluations a product). Gershgorin's bound above is
// safe but loose, most of all for the damping (single_sphere at rest: gamma 1382 1/s bounded, 392
// 1/s found; omega 331 against 218 rad/s). Both approach the largest eigenvalue from below; each
// call starts from the last call's mode, so along a run a few iterations follow it.
// Deterministic: the force stages are bit-identical on any thread count and the sums here run in
// vertex order.
class ModeEstimator {
 public:
  // Reads the model and evaluates its forces through `forces` (both must outlive this object).
  explicit ModeEstimator(const Forces& forces);
  explicit ModeEstimator(const World& world) : ModeEstimator(world.forces()) {}
  struct Rates {
    double omega = 0, gamma = 0;  // [rad/s], [1/s]
    double stiffGamma = 0;        // the stiff mode's own damping rate (u^T D u, u that mode) [1/s]
    uint32_t body = 0;            // the body holding most of the stiff mode
    // The vertices (model indices) with the largest share of the stiff and of the most damped
    // mode: where each mode is.
    uint32_t stiffVertex = 0, dampedVertex = 0;
  };
  // What sets step(): the stiff mode, or the damping (without it the step would be longer).
  enum class Limit { Stiffness, Damping };
  Rates estimate(const std::vector<Vec3>& x, int iterations);
  // The largest step of `integrator` stable on every mode with frequency up to omega and damping
  // rate up to gamma: the stiff mode as found, undamped (except for explicit Euler, which no
  // undamped mode leaves stable, so it takes the stiff mode with its own damping: the largest
  // damping rate may belong to another mode, and the folded hinge case failed at 0.6 of the step
  // paired with it), and a mode as damped with no stiffness (the two rates need not belong to one
  // mode; margin: all raised by 5% for the iteration's shortfall).
  static double step(Integrator integrator, const Rates& rates, double horizon, Limit* limit = nullptr);

 private:
  // y = the mass-normalised stiffness (or damping) times u, by central differences.
  void product(const std::vector<Vec3>& x, bool damping, const std::vector<Vec3>& u, std::vector<Vec3>& y);
  // Power iteration (the damping), and Lanczos (the stiffness, which can be indefinite); u: the
  // start, and on return the mode found.
  double iterate(const std::vector<Vec3>& x, bool damping, std::vector<Vec3>& u, int iterations);
  double lanczos(const std::vector<Vec3>& x, std::vector<Vec3>& u, int steps);
  const Forces& forces_;
  std::vector<double> invSqrtMass_;
  std::vector<Vec3> stiff_, damped_, probe_, plus_, minus_, fPlus_, fMinus_, zero_, y_;
  std::vector<std::vector<Vec3>> basis_;  // Lanczos's vectors
  std::vector<double> alpha_, beta_;      // and its tridiagonal matrix
  double epsilon_;  // the differences' largest displacement [m] (or velocity [m/s])
};

// The advisor through a whole run (a survey): the estimate holds at the shape it is made at, and
// an impact compresses a body, which stiffens it (a hinge's gradient grows as its triangles
// flatten). The survey runs the model over `duration` with the default adaptive step (its step
// chosen by tolerance and kept under the same mode's limit, so the survey needs no step of its
// own). It finds the stiffest mode (above) at every frame, and at every `interval` (at least a
// 64th of a frame, at most a frame) where Gershgorin's limit comes within 1.5 of the smallest it
// has seen (a stiffening shape); and at every frame the step each body's landing allows (its
// energy error, sim/monitor.h landingStep, at the monitor's tolerance). The smallest step over
// the run is its limit.
struct StabilitySurvey {
  double dtMax = std::numeric_limits<double>::infinity();  // smallest over the run [s]
  double atRest = std::numeric_limits<double>::infinity(); // the estimate at t = 0 [s]
  double gershgorin = std::numeric_limits<double>::infinity();  // Gershgorin's smallest, for comparison [s]
  double time = 0.0;                                        // when the smallest was seen [s]
  uint32_t body = 0;                                        // and in which body
  uint32_t estimates = 0;                                   // mode estimates made
  bool landing = false;  // the smallest is a landing's (sim/monitor.h landingStep), not a mode's
  // A mode's: which limit set it, its rate (omega [rad/s] or the damping rate [1/s]), and the
  // vertex (model index) with the largest share of that mode, and where it was then.
  ModeEstimator::Limit limit = ModeEstimator::Limit::Stiffness;
  double rate = 0.0;
  uint32_t vertex = 0;
  Vec3 position;
  std::string failure;  // non-empty if the survey run itself failed (the limit then covers the run up to it)
};
// `initial`: the positions at t = 0 (null: the rest shape), as for a case released deformed.
// `landingTolerance`: the energy rise a landing may add, as a fraction (the monitor's: 2 %).
StabilitySurvey surveyStability(const Model& model, Integrator integrator, double duration, double frame,
                                double interval, double tolerance, unsigned threads = 1,
                                const std::vector<Vec3>* initial = nullptr, double landingTolerance = 0.02);

// Substeps that bring dt below safety * dtMax (at least 1).
int safeSubsteps(double dt, double dtMax, double safety = 0.9);

}  // namespace springy

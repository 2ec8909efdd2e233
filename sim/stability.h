// springy: the stability advisor. Before running, estimate each body's highest natural
// frequency and strongest damping rate, and from them the largest stable time step of the
// chosen integrator; propose parameters for a given time step (the seed's future work 4.4).
//
// Estimate. The stiffest mode of a body is an eigenvector of M^-1/2 K M^-1/2 (and of the
// damping matrix D likewise). Gershgorin's theorem bounds every eigenvalue by the largest row
// sum of absolute values; with 3x3 blocks, row i sums ||K_ij|| / sqrt(m_i m_j) over the
// vertices j it shares a strut or hinge with (pinned neighbours drop out: they do not move).
// A strut's block norm is k max(1, |1 - l0/l|) (its transverse stiffness when compressed), a
// hinge's k |g_i| |g_j| with g the angle's gradient at the current shape; damping likewise with
// d, plus the drag and deformation damping rates. Each row gives omega_i^2 and gamma_i; the integrator's stability on the
// test mode x'' = -omega_i^2 x - gamma_i x' bounds its step.
//
// Stability of an integrator on that mode: the spectral radius rho(h) of its one-step
// amplification matrix (computed by applying the integrator's own update to the 2x2 system).
// A step is stable when rho(h)^(horizon/h) <= sqrt(2), i.e. no mode more than doubles its
// energy over the run: symplectic and higher-order methods are stable below a sharp limit (2/omega for
// symplectic Euler, Verlet and leapfrog, about 2.8/omega for RK4); explicit Euler, which
// amplifies every undamped mode, gets the step at which the growth over the horizon stays
// within that tolerance (so its limit shrinks as the run gets longer). Backward Euler is unconditionally stable on every linear mode.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "sim/model.h"
#include "sim/world.h"
#include "sim/monitor.h"

namespace springy {

// Mass-normalised Gershgorin row sums of one vertex [1/s^2 for stiffness, 1/s for damping].
struct RowBound {
  uint32_t vertex;
  double strutStiffness = 0, hingeStiffness = 0, strutDamping = 0, hingeDamping = 0, drag = 0;
  // The enclosed gas's breathing mode, omega^2 = (p0 V0 / V^2) sum_j |g_j|^2 / m_j: one
  // eigenvalue of the whole body, added to every row (the largest eigenvalue of a sum is at
  // most the sum of the largest eigenvalues). The pressure's curvature term p d^2V/dx^2 is left
  // out: it vanishes at rest, but in a strongly compressed body the limit is then optimistic
  // (docs/stability.md, "stiff gas": measured 0.3-0.8 of the prediction).
  double gasStiffness = 0;
};

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

// Spectral radius of the integrator's one-step map on x'' = -omega^2 x - gamma x'.
double amplification(Integrator integrator, double omega, double gamma, double h);

// Largest h with amplification(h)^(horizon/h) <= sqrt(2) (infinity for backward Euler or a mode
// with neither stiffness nor damping).
double criticalStep(Integrator integrator, double omega, double gamma, double horizon);

// Gershgorin rows of one body at positions x.
std::vector<RowBound> gershgorinRows(const Model& model, const Vec3* x, uint32_t body);

// The estimate for one body from its rows.
BodyStability bodyStability(const std::vector<RowBound>& rows, Integrator integrator, double horizon,
                            const ParameterScale& scale = {});

// The estimate for every body of a model at positions x (its state at t = 0, usually).
StabilityReport estimateStability(const Model& model, const std::vector<Vec3>& x, Integrator integrator,
                                  double horizon);

// Substeps that bring dt below safety * dtMax (at least 1).
int safeSubsteps(double dt, double dtMax, double safety = 0.9);

// Measurement: one run of `horizon` seconds under the stability monitor (finite, no blow-up
// beyond 10 times the rest size, energy never more than its scale above the start; checked
// every few steps and at the end).
struct RunOutcome {
  bool stable = true;
  std::string failure;   // the monitor's message when not stable
  std::string kind;      // "nan", "blow-up", "energy", "penetration", "volume" or "" when stable
  uint64_t step = 0;     // the step at which it failed
  bool finiteAtEnd = true;  // every position and velocity finite when the run stopped
};
RunOutcome runMonitored(const Model& model, Integrator integrator, double dt, double horizon,
                        const std::vector<Vec3>* initialPositions = nullptr);

// Largest stable step found by bisection (in log dt) between a stable and an unstable step
// bracketing `guess`; `failure` is what failed first just above it. dt is capped at maxDt
// (reported with capped = true when still stable there).
struct MeasuredStep {
  double dt = 0;
  bool capped = false;
  RunOutcome above;  // the run just above the limit
};
MeasuredStep largestStableStep(const Model& model, Integrator integrator, double horizon, double guess, double maxDt,
                               const std::vector<Vec3>* initialPositions = nullptr, int iterations = 10);

// The stiff and extreme cases of the stability study (`springy study stability`) and its tests.
struct StabilityCase {
  std::string name;
  std::string description;
  Model model;
  std::vector<Vec3> positions;  // the state at t = 0 (may differ from the rest shape)
};
struct CaseFactory {
  std::string name;
  bool degenerate = false;  // must be refused at load
  bool stiff = false;       // every explicit integrator needs steps 100 times below 1/60 s
  std::function<StabilityCase()> make;  // throws springy::Error when refused
};
// Two unit masses on one strut of period P and decay time T (decay 0: undamped), released
// stretched by 10 %.
StabilityCase strutCase(double period, double decay);
// Two triangles on one hinge (period P_theta, decay T_theta; 0: undamped) with struts of period 2 P_theta,
// rest angle restAngle, released at startAngle.
StabilityCase hingeCase(double period, double decay, double restAngle = 0.5, double startAngle = 0.9);
std::vector<CaseFactory> stabilityCases();

}  // namespace springy

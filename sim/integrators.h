// springy: the integrators, as one table (integratorTraits): what each is, read by the world (its
// refusals), the scene reader and the run options (their refusals), the advisor, the monitor
// (whose energy criterion depends on it) and the studies (orders, costs).
#pragma once

#include <string>
#include <string_view>

namespace springy {

enum class Integrator {
  ExplicitEuler,    // x += dt v(t), v += dt a(t)                            order 1
  SymplecticEuler,  // v += dt a(t), x += dt v(t + dt)                       order 1
  VelocityVerlet,   // x += dt v + dt^2/2 a, v += dt/2 (a + a_new)           order 2, 1 eval/step
  Leapfrog,         // kick dt/2, drift dt, kick dt/2 (forces at both ends)  order 2, 2 evals/step
  RK4,              // classical Runge-Kutta, forces at all four stages      order 4
  BackwardEuler,    // implicit: Newton + CG on M dv = h f(x + h v1, v1)     order 1 (sim/implicit.h)
  BogackiShampine,  // adaptive: embedded 3(2) pair, step chosen by a tolerance order 3, 3 evals/step
  AdaptiveVerlet,   // adaptive: velocity Verlet, error from a1 - a0              order 2, 1 eval/step
  Vbd,              // implicit: vertex block descent on backward Euler's potential  order 1 (sim/vbd.h)
};

struct IntegratorTraits {
  Integrator integrator;
  std::string_view name;  // in scene files and on the command line
  int order;              // of convergence (its global error is O(h^order))
  // Force evaluations a step costs (the implicit ones: an explicit evaluation's worth of work per
  // Newton iteration or sweep, typically 10-20 a step; 0 here).
  int evaluations;
  bool implicit;          // solves for the step's end: no stability limit on the step
  bool adaptive;          // chooses its own step by a tolerance (World::setTolerance)
  bool takesIterations;   // [scene] iterations / --iterations: its sweeps per step
  // What its solve can hold: colliders that move on their own, soft attachments ([[attach]]).
  bool movingColliders, softAttachments;
  // Symplectic: at a stable step its energy is bounded but, read at an instant, swings about its
  // conserved value by up to 1/(1 - (omega h)^2/4) of a mode's (5 times at omega h = 1.8); the
  // others' only falls at a stable step (RK4 and Bogacki-Shampine damp every mode they keep,
  // backward Euler every mode), or rises at every step (explicit Euler). The monitor reads it.
  bool energySwings;
};

const IntegratorTraits& integratorTraits(Integrator integrator);

inline bool isAdaptive(Integrator i) { return integratorTraits(i).adaptive; }
inline bool isImplicit(Integrator i) { return integratorTraits(i).implicit; }
inline bool energySwings(Integrator i) { return integratorTraits(i).energySwings; }
inline std::string_view integratorName(Integrator i) { return integratorTraits(i).name; }
// The integrator a tolerance alone selects.
constexpr Integrator kDefaultAdaptive = Integrator::AdaptiveVerlet;

// Parses a name; returns false if unknown.
bool parseIntegrator(std::string_view name, Integrator& out);
// Comma-separated list of all names, for error messages.
std::string integratorNames();
// What the integrator cannot run in this model, as the refusal's words ("colliders that move",
// "soft attachments ([[attach]] with a period)"), or empty.
std::string integratorRefuses(Integrator integrator, bool movingColliders, bool softAttachments);

}  // namespace springy

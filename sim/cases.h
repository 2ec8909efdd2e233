// springy: the shared set-ups of the tests, the studies and the benchmarks (as Box2D's
// shared/): the stiff and extreme cases of the stability study and the small strut and hinge
// systems the accuracy study and the tests measure.
#pragma once

#include <functional>
#include <utility>
#include <string>
#include <vector>

#include "sim/model.h"

namespace springy {

// Hand-built models the tests, the studies and the benchmarks share: no mesh, no scene.
// One free vertex of the given mass, no colliders.
Model vertexModel(const Vec3& position, const Vec3& velocity, const Vec3& gravity, double mass = 1.0);
// Two vertices joined by one strut along x, no gravity, no colliders.
Model strutModel(double m0, double m1, double restLength, double k, double d, bool pinFirst);
// Two triangles (0, 1, 2) and (1, 0, 3) sharing the edge 0-1 along x, folded to `angle` (the
// signed dihedral angle; left wing in the y > 0 half-plane tilted down by angle / 2, right wing
// mirrored: positive = convex, normals along +z when flat).
std::vector<Vec3> hingePositions(double angle);
// Those triangles with unit masses, one hinge (rest angle, k_theta, d_theta) and optionally the
// five struts of their edges (k, d).
Model hingeModel(double restAngle, double k, double d, bool withStruts, double strutK = 0.0, double strutD = 0.0);
// The forces of hinges [begin, end) added to f, each hinge's kernel constants (HingeTerms)
// derived on the spot: for a few hinges in a test, where the stage list's cached terms are not at
// hand.
void applyHingesDerivingTerms(const Hinge* hinges, std::size_t begin, std::size_t end, const Vec3* x, const Vec3* v,
                              Vec3* f);

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

// springy: the shared set-ups of the tests, the studies and the benchmarks (as Box2D's
// shared/): the stiff and extreme cases of the stability study and the small strut and hinge
// systems the accuracy study and the tests measure.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "sim/model.h"

namespace springy {

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

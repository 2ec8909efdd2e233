// springy: the state a World advances, what changes as a run goes (sim/model.h holds what does
// not): positions and velocities, the clock, and the inverse masses a pin's release changes.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/model.h"

namespace springy {

struct State {
  std::vector<Vec3> x, v;       // per vertex, model order [m], [m/s]
  double time = 0.0;            // [s]
  uint64_t steps = 0;           // steps taken (the adaptive step: accepted ones)
  // Per vertex: 1 / m, or 0 while it is held (pinned); a pin released (Model::PinTrack::release)
  // gets its 1 / m here. Starts as the model's (Model::invMass: the masses as set up).
  std::vector<double> invMass;
  std::vector<uint8_t> released;  // per pin track (Model::pinTracks): released yet
};

}  // namespace springy

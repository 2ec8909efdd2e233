// springy: measurements of a world's state, per body: energies, volume, strain, size,
// penetration. Used by `springy check`, the traces, the tests and the stability checks.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/world.h"

namespace springy {

struct BodyMeasures {
  Vec3 centroid;            // mass-weighted [m]
  Vec3 momentum;            // [kg m/s]
  Vec3 angularMomentum;     // about the origin [kg m^2/s]
  double kinetic = 0.0;     // [J]
  double gravitational = 0.0;  // -sum m g . x [J] (zero at the origin)
  double elastic = 0.0;     // struts + hinges + enclosed gas [J]
  double volume = 0.0;      // [m^3]; 0 for an open surface (BodyInfo::open)
  double size = 0.0;        // bounding-box diagonal [m]
  double maxStrain = 0.0;   // max |l - l0| / l0 over struts
  double penetration = 0.0; // deepest vertex behind a plane collider [m]
  double rmsSpeed = 0.0;    // [m/s]
  bool finite = true;       // every position and velocity finite
  double total() const { return kinetic + gravitational + elastic; }
};

BodyMeasures measureBody(const World& world, uint32_t body);
// The same of a state (x, v) other than the world's (e.g. World::synchronizedState).
BodyMeasures measureBody(const World& world, uint32_t body, const Vec3* x, const Vec3* v);

// FNV-1a over the raw bits of positions, velocities and time: equal hashes mean bit-identical
// states.
uint64_t stateHash(const World& world);

}  // namespace springy

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

// How fast a body can answer what pushes it, from its struts at rest: omega^2 = mean k / mean
// vertex mass (a vertex on one strut), its waves' speed c = mean rest length * omega (a chain of
// such struts), and how far it would sag under its own weight in gravity g: a chain of n =
// restSize / length struts hanging from one end stretches by g n^2 / (2 omega^2). Estimates, to
// tell a scene that asks the impossible from a step too coarse, not physics to report. A body
// without struts gives omega 0: nothing is told about it.
struct BodyResponse {
  double omega = 0.0;   // [rad/s]
  double length = 0.0;  // mean strut rest length [m]
  double speed() const { return length * omega; }  // [m/s]
  double sag(double g, double restSize) const;     // [m]
};
BodyResponse bodyResponse(const Model& model, uint32_t body);

// What the scene drives `body` with, over the time from `since` to the world's time, that no step
// can follow, or "" when nothing stands out (then the step may be at fault): gravity that would
// sag the body by more than ten times its size ("gravity 1e+06 m/s^2 (it would sag the body by 125 m
// under its own weight, 7.4 times its size)"), or a moving collider or the body's pins faster than
// its waves run ("collider 'plate' moving at 1000 m/s (its keyframes at t = 0.3 s and 0.3015 s
// move it 1.5 m in 0.0015 s), more than the 18.82 m/s at which the body can give way"), over ten
// times. A driver much faster than the body answers crushes it or tears through it whatever the
// step: a failure with such a cause is the scene's (Failure::cause, sim/monitor.h).
std::string sceneCause(const World& world, uint32_t body, double since);

// FNV-1a over the raw bits of positions, velocities and time: equal hashes mean bit-identical
// states.
uint64_t stateHash(const World& world);

}  // namespace springy

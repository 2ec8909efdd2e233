// springy: stability monitoring. Never hide instability: a run is watched for non-finite
// values, bodies growing far beyond their rest size, total energy rising when nothing injects
// energy, vertices behind a plane, and closed bodies turned inside out or crushed flat. The first
// failure stops the run with a message that names the body, the step and the simulated time, and
// suggests what to try; when the scene drives the body harder than it can follow (gravity, a
// collider or pins too fast), it names that instead of blaming the step.
//
// What a body can do between two frames and undo by the next (turn inside out, collapse, go NaN
// and take the run with it) is watched every step (Monitor::watchStep, from stepTo): a pass over
// the faces and vertices, a few percent of a step. The rest (energies, sizes, crossings) at frames.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/diagnostics.h"

namespace springy {

struct MonitorLimits {
  double sizeFactor = 10.0;        // a body larger than this times its rest size has blown up
  double energyTolerance = 0.02;   // allowed rise of total energy, as a fraction of its scale
  bool energyFromLowest = true;    // the rise counts from the lowest total so far (energy pumped
                                   // into a body that has lost most of it), not only from the
                                   // start; the stability study measures from the start, the
                                   // classical bounded-energy criterion
  double penetration = 1e-4;       // allowed depth behind a plane, as a fraction of body size
  double minVolume = 0.0;          // a body whose volume falls below this fraction of rest has
                                   // collapsed (0: not checked)
};

struct Failure {
  uint32_t body;
  uint64_t step;
  double time;
  std::string message;     // complete, ready to print
  bool criterion = false;  // a limit the run was given (MonitorLimits::minVolume), not an instability
  // What the scene did that no step can fix (sim/diagnostics.h sceneCause: "gravity 1e+06
  // m/s^2 ...", "collider 'plate' moving at 1000 m/s ..."); empty when the step may be at fault.
  std::string cause = {};
};

// A closed body whose volume falls to this share of its rest volume (or of its volume at the last
// frame) has collapsed: crushed flat, folded through itself or inside out. Far below what a body
// that keeps its shape comes to (scenes/press.toml's ball, squeezed to half its height, keeps 81%).
constexpr double kCollapsedVolume = 0.01;

// Per-body running extremes, for reports.
struct BodyRecord {
  BodyMeasures start, last;
  double energyScale = 0.0;   // [J] the energy the body has to spend at the start: kinetic +
                              // elastic + its fall to its support (at least its own size)
  double lowestTotal = 0.0;   // [J] the lowest total energy so far, and when
  double lowestTotalTime = 0.0;
  double lowestSpendable = 0.0;  // [J] what it had left to spend then (as energyScale, measured
                                 // at that moment, without the floor of its own size): a rise
                                 // above the lowest is measured against it (Monitor::check)
  double maxStrain = 0.0;
  double maxPenetration = 0.0;
  double minVolumeRatio = 1.0, maxVolumeRatio = 1.0;
};

// At rest over a stretch of time, as a viewer sees it: every vertex stays inside a box no
// larger (diagonal) than 0.2% of its body's size over the frames watched (for a ball filling
// a fifth of a 720p frame, 0.4 pixel). Unlike a speed threshold at one instant, a bounce's apex
// does not pass, and neither does a slow drift; a vibration too small to see does.
// `springy check --end-at-rest` watches the last second of a run.
class RestWatch {
 public:
  static constexpr double kFraction = 2e-3;  // of the body's rest size
  static constexpr double kWindow = 1.0;     // [s] what --end-at-rest watches

  void add(const std::vector<Vec3>& x);  // one frame
  bool empty() const { return lo_.empty(); }
  // The largest box diagonal of the body's vertices [m] and the (model) vertex that has it.
  std::pair<double, uint32_t> largestMove(const BodyInfo& info) const;
  bool atRest(const BodyInfo& info) const { return !empty() && largestMove(info).first <= kFraction * info.restSize; }

 private:
  std::vector<Vec3> lo_, hi_;
};

// The step at which a landing adds the monitor's tolerance of energy: a vertex that lands at
// speed v sinks about v h behind its support in a step, and being put back on it lifts it by as
// much, m g v h for the body, while the bounce takes (1 - e^2) m v^2 / 2 (restitution e, the
// most elastic collider's). Against `tolerance` times what the body has left to spend (kinetic +
// elastic + its centroid's fall to the lowest support, the monitor's measure):
// h = tolerance E / (M g v) + (1 - e^2) v / 2g, v the speed it lands at (from its kinetic energy
// and its lowest vertex's fall). The cube scene (restitution 1, dropped 15 m): 0.0233 s, where
// its runs fail from 0.0236 s (docs/stability.md). Infinite without gravity or colliders, or for
// a body at rest on its support.
double landingStep(const World& world, uint32_t body, double tolerance);

class Monitor {
 public:
  Monitor(const World& world, MonitorLimits limits = {});
  // Measures every body; returns the first failure, if any. Call as often as you like (every
  // output frame is typical): each call costs one pass over the vertices and elements.
  // A failure watchStep saw comes first.
  std::optional<Failure> check(const World& world);
  // The checks a run makes after every step, so that nothing between two frames passes: every
  // closed body's volume (at or below zero, or collapsed: kCollapsedVolume) and every open one's
  // positions finite. O(faces + vertices); the failure, if any, is kept for check().
  std::optional<Failure> watchStep(const World& world);
  const std::optional<Failure>& watched() const { return watched_; }
  // Since when a failure now is looked for a cause in the scene (the check before the last).
  double since() const { return checkedAt_[0]; }
  const std::vector<BodyRecord>& records() const { return records_; }
  // The volume limit from the next check on (MonitorLimits::minVolume; 0: not checked).
  void setMinVolume(double fraction) { limits_.minVolume = fraction; }
  bool energyChecked() const { return checkEnergy_; }

 private:
  MonitorLimits limits_;
  std::optional<Failure> watched_;  // watchStep's failure
  std::vector<double> frameVolume_;  // per body: its volume at the last check [m^3]
  // The times of the last two checks: what drove a body is looked for since the earlier
  // (sceneCause), so that a jump just before a frame is still seen after it.
  double checkedAt_[2] = {0.0, 0.0};
  bool checkEnergy_;
  bool lowestBased_;  // a rise from the lowest measured against what was left then (not the start's scale)
  std::vector<BodyRecord> records_;
  // Bodies that touch each other (sim/contact.h) pass energy between them: their energy is
  // checked as one sum, which nothing may raise.
  std::vector<uint32_t> touching_;
  Vec3 up_;                       // against gravity
  double g_ = 0.0;                // |gravity|
  std::vector<double> support_;   // per body: the height its fall ends at (along up_)
  // The energy a body still has to spend in the state m: kinetic + elastic + its fall to its
  // support (of its centroid, at least leastFall).
  double spendable(const BodyInfo& info, uint32_t body, const BodyMeasures& m, double leastFall) const;
  // A rise of a body's energy is confirmed at one instant before it counts: symplectic Euler's
  // positions and velocities are half a step apart, and their energy swings by up to
  // 1/(1 - omega h/2) where the method keeps it (World::synchronizedState). Only then, so that a
  // run that passes pays nothing for it; the confirmed energies replace the body's (m).
  void readAtOneInstant(const World& world, uint32_t body, BodyMeasures& m);
  // Steps of check(). One body: finite, not blown up, its energy not risen (unless it touches
  // others), not behind a plane, its volume above the limit; its record updated.
  std::optional<Failure> checkBody(const World& world, uint32_t body);
  // check() less watchStep's failure and the clock of checks.
  std::optional<Failure> checkAll(const World& world);
  // The bodies that touch each other: their energy summed, which nothing may raise.
  std::optional<Failure> checkTouchingEnergy(const World& world);
  enum class Synchronized { NotYet, Yes, No };  // in this check
  Synchronized synchronized_ = Synchronized::NotYet;
  std::vector<Vec3> xSync_, vSync_;
  double touchingScale_ = 0.0, touchingLowest_ = 0.0, touchingLowestTime_ = 0.0, touchingSpendable_ = 0.0;
};

// Steps `world` toward `time` until it reaches it (within half a step; the adaptive step lands on
// it exactly). Returns false when it stopped short: the adaptive step could not meet its
// tolerance (World::stepProblem), or an interruption was requested (sim/interrupt.h), polled
// before every step so that a long frame (a fine step, a large model) stops at once.
// With `monitor`, its watchStep after every step: false too when it fails.
bool stepTo(World& world, double time, Monitor* monitor = nullptr);

// A failure of the step (World::stepProblem) at the world's time, with what the scene did, if
// anything, to any body since `since` (sceneCause): an adaptive step that shrinks to nothing at a
// collider's jump is the jump's failure, not the tolerance's.
Failure stepFailure(const World& world, double since);

// stepTo, then the monitor's check: the failure, if any (the monitor's first, since a blow-up it
// sees says more than the step's problem). Nothing when interrupted: the caller sees
// interrupted() and stops. The one way every run (check, render, the Python module, the
// advisor's tries, the studies) moves a world from one frame to the next.
std::optional<Failure> advanceTo(World& world, Monitor& monitor, double time);

}  // namespace springy

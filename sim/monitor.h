// springy: stability monitoring. Never hide instability: a run is watched for non-finite
// values, bodies growing far beyond their rest size, total energy rising when nothing injects
// energy, and vertices behind a plane. The first failure stops the run with a message that
// names the body, the step and the simulated time, and suggests what to try.
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
  double penetration = 1e-4;       // allowed depth behind a plane, as a fraction of body size
  double minVolume = 0.0;          // a body whose volume falls below this fraction of rest has
                                   // collapsed (0: not checked)
};

struct Failure {
  uint32_t body;
  uint64_t step;
  double time;
  std::string message;  // complete, ready to print
};

// Per-body running extremes, for reports.
struct BodyRecord {
  BodyMeasures start, last;
  double energyScale = 0.0;   // [J] the energy a failure is measured against
  double maxStrain = 0.0;
  double maxPenetration = 0.0;
  double minVolumeRatio = 1.0, maxVolumeRatio = 1.0;
};

// A body is at rest when its vertices' RMS speed is below 0.2% of its rest size per second
// (e.g. 0.04 m/s for the 20 m diagonal of a radius-6 ball): still enough that no motion shows
// in a video frame.
inline bool atRest(const BodyMeasures& m, const BodyInfo& info) { return m.rmsSpeed < 2e-3 * info.restSize; }

class Monitor {
 public:
  Monitor(const World& world, MonitorLimits limits = {});
  // Measures every body; returns the first failure, if any. Call as often as you like (every
  // output frame is typical): each call costs one pass over the vertices and elements.
  std::optional<Failure> check(const World& world);
  const std::vector<BodyRecord>& records() const { return records_; }
  bool energyChecked() const { return checkEnergy_; }

 private:
  MonitorLimits limits_;
  bool checkEnergy_;
  std::vector<BodyRecord> records_;
};

}  // namespace springy

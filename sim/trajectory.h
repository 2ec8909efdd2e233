// springy: a whole run's path as a viewer and a report see it, and its error against a
// reference run: the measure of accuracy through contact (docs/accuracy.md, "Through contact").
//
// A run is sampled at its output frames (where a video shows it): each body's centroid and
// volume. Two runs of the same scene compare frame by frame; fixed steps that divide the frame
// interval and the adaptive step (which lands on every frame) sample at the same times, so no
// interpolation blurs the comparison.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/model.h"
#include "sim/world.h"

namespace springy {

// The frames a run of `duration` samples at one every `frame` seconds: at least one. check, render
// and the advisor's tries count them alike, so a check sees the states a video shows.
inline long frameCount(double duration, double frame) { return std::max(1L, std::lround(duration / frame)); }

struct PathSettings {
  Integrator integrator = Integrator::RK4;
  double dt = 0.002;        // fixed steps; the adaptive integrator's first step
  double tolerance = 1e-4;  // the adaptive integrator's
  double frame = 1.0 / 30;  // output interval [s]
  double duration = 1.0;    // [s]
  unsigned threads = 1;
};

struct RunPath {
  std::vector<double> times;                // the frames reached
  std::vector<std::vector<Vec3>> centroid;  // [frame][body]
  std::vector<std::vector<double>> volume;  // [frame][body] (0 for an open surface)
  std::vector<double> energy, kinetic;      // [frame] totals over the bodies [J]
  bool complete = false;                    // reached the duration under the monitor
  std::vector<bool> endsAtRest;             // [body] still over the last second (RestWatch)
  std::string failure;                      // the monitor's message otherwise
  // The stepping alone (no sampling), as the calling thread's CPU time (sim/parallel.h
  // threadCpuSeconds): with settings.threads = 1 the stepping's whole cost, which runs side by
  // side on other cores do not inflate (the studies run theirs so) [s].
  double stepSeconds = 0.0;
  uint64_t steps = 0, evaluations = 0;
  StepStats stepStats;  // the adaptive integrator's
};

// Runs the model under the stability monitor, sampling every frame. Stops at the first failure.
RunPath tracePath(const Model& model, const PathSettings& settings);

// Runs of one scene at several steps (the advisor's tries, the stability study): every body that
// came to rest in the first complete run must come to rest in each later one, or that run carries
// an instability the monitor's energy check does not see (saturated under its tolerance). The
// first complete run given sets the reference; returns the first body that no longer comes to
// rest, or -1.
int bodyNoLongerAtRest(std::vector<bool>& restsAtFirst, const RunPath& run);

// The error of `run` against `reference` (same model, same frames), the largest over bodies:
struct PathError {
  double centroidRms = 0.0;   // RMS over frames of the centroid's distance, / body size
  double endPosition = 0.0;   // the last frame's centroid distance, / body size
  double lowestVolume = 0.0;  // |lowest volume - reference's| / reference's (closed bodies)
  // Energy: the run's total at the last frame below the reference's (what it dissipates beyond
  // the physics: its numerical damping) [J], and that over the reference's largest kinetic energy
  // (the energy of the motion, e.g. a drop's at its impact).
  double energyLost = 0.0, energyLostShare = 0.0;
  uint32_t body = 0;          // the body with the largest centroidRms
};
// Throws std::invalid_argument when the runs do not share their frames (an incomplete run has
// no error: its failure is the answer).
PathError pathError(const Model& model, const RunPath& reference, const RunPath& run);

}  // namespace springy

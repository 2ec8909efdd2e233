#include "sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sim/diagnostics.h"
#include "sim/monitor.h"
#include "sim/parallel.h"

namespace springy {

int bodyNoLongerAtRest(std::vector<bool>& restsAtFirst, const RunPath& run) {
  if (restsAtFirst.empty()) {
    restsAtFirst = run.endsAtRest;
    return -1;
  }
  for (std::size_t b = 0; b < restsAtFirst.size() && b < run.endsAtRest.size(); ++b) {
    if (restsAtFirst[b] && !run.endsAtRest[b]) return static_cast<int>(b);
  }
  return -1;
}

RunPath tracePath(const Model& model, const PathSettings& settings) {
  World world(model, settings.integrator, settings.dt);
  if (world.adaptive()) world.setTolerance(settings.tolerance);
  world.setThreads(settings.threads);
  Monitor monitor(world);
  RunPath path;
  const long frames = frameCount(settings.duration, settings.frame);
  const auto sample = [&] {
    path.times.push_back(world.time());
    path.centroid.emplace_back();
    path.volume.emplace_back();
    double energy = 0.0, kinetic = 0.0;
    for (uint32_t b = 0; b < model.bodies.size(); ++b) {
      const BodyMeasures m = measureBody(world, b);
      path.centroid.back().push_back(m.centroid);
      path.volume.back().push_back(m.volume);
      energy += m.total();
      kinetic += m.kinetic;
    }
    path.energy.push_back(energy);
    path.kinetic.push_back(kinetic);
  };
  sample();
  double seconds = 0.0;
  RestWatch rest;  // over the last second, as `springy check --end-at-rest`
  const double watchFrom = settings.duration - RestWatch::kWindow;
  for (long f = 1; f <= frames; ++f) {
    const double until = static_cast<double>(f) * settings.frame;
    const double start = threadCpuSeconds();
    const bool reached = stepTo(world, until, &monitor);  // watched every step, as a run is
    seconds += threadCpuSeconds() - start;
    if (!reached && world.stepProblem().empty() && !monitor.watched()) {
      path.failure = "interrupted";
      break;
    }
    if (const auto failure = monitor.check(world)) {
      path.failure = failure->message;
      break;
    }
    if (!world.stepProblem().empty()) {
      path.failure = world.stepProblem();
      break;
    }
    sample();
    if (world.time() >= watchFrom - 1e-9) rest.add(world.positions());
  }
  path.complete = path.failure.empty();
  for (uint32_t b = 0; b < model.bodies.size() && path.complete; ++b)
    path.endsAtRest.push_back(rest.atRest(model.bodies[b]));
  path.stepSeconds = seconds;
  path.steps = world.stepCount();
  path.evaluations = world.forceEvaluations();
  path.stepStats = world.stepStats();
  return path;
}

PathError pathError(const Model& model, const RunPath& reference, const RunPath& run) {
  if (!run.complete || !reference.complete || run.times.size() != reference.times.size()) {
    throw std::invalid_argument("pathError: the runs do not share their frames");
  }
  PathError out;
  const std::size_t frames = run.times.size();
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    const double size = model.bodies[b].restSize;
    double sum = 0.0, lowestRef = reference.volume[0][b], lowestRun = run.volume[0][b];
    for (std::size_t f = 0; f < frames; ++f) {
      const double d = length(run.centroid[f][b] - reference.centroid[f][b]);
      sum += d * d;
      lowestRef = std::min(lowestRef, reference.volume[f][b]);
      lowestRun = std::min(lowestRun, run.volume[f][b]);
    }
    const double rms = std::sqrt(sum / static_cast<double>(frames)) / size;
    if (rms > out.centroidRms || b == 0) {
      out.centroidRms = rms;
      out.body = b;
    }
    out.endPosition =
        std::max(out.endPosition, length(run.centroid[frames - 1][b] - reference.centroid[frames - 1][b]) / size);
    if (lowestRef > 0.0) out.lowestVolume = std::max(out.lowestVolume, std::fabs(lowestRun - lowestRef) / lowestRef);
  }
  if (!run.energy.empty() && run.energy.size() == reference.energy.size()) {
    out.energyLost = reference.energy.back() - run.energy.back();
    const double motion = *std::max_element(reference.kinetic.begin(), reference.kinetic.end());
    out.energyLostShare = motion > 0.0 ? out.energyLost / motion : 0.0;
  }
  return out;
}

}  // namespace springy

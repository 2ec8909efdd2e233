#include "run/run.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <limits>

#include "run/advisor.h"
#include "run/load.h"
#include "sim/interrupt.h"
#include "sim/trajectory.h"

namespace springy {

Run::Run(std::string path, RunOptions options, const std::function<void(SceneDesc&)>& edit)
    : path_(std::move(path)), options_(std::move(options)) {
  scene_ = loadSceneWith(path_, options_, true, &untried_);
  if (edit) edit(scene_);
  frameTime_ = 1.0 / scene_.view.render.fps;
  frames_ = frameCount(scene_.duration, frameTime_);
  restart();
}

void Run::restart() {
  if (keepReplaced_ && world_) replaced_.push_back(std::move(*world_));
  world_.reset();  // its threads and buffers go before the new ones come
  world_.emplace(makeWorld(scene_, options_));
  MonitorLimits limits;
  limits.minVolume = options_.minVolume;
  monitor_.emplace(*world_, limits);
  rest_ = RestWatch{};
  frame_ = 0;
  pristine_ = true;
  failure_.reset();
  startedAt_ = std::chrono::steady_clock::now();
}

double Run::wallSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - startedAt_).count();
}

void Run::start() {
  startedAt_ = std::chrono::steady_clock::now();
  for (RunObserver* o : observers_) o->started(*this);
}

const std::optional<Failure>& Run::fail(std::optional<Failure> failure) {
  if (failure) failure_ = std::move(failure);
  return failure_;
}

const std::optional<Failure>& Run::nextFrame() {
  if (failure_) return failure_;
  const long k = frame_ + 1;
  std::optional<Failure> failure = advanceTo(*world_, *monitor_, static_cast<double>(k) * frameTime_);
  if (!failure && interrupted()) return failure_;  // stopped within the frame: not reached
  frame_ = k;
  pristine_ = false;
  if (world_->time() >= scene_.duration - RestWatch::kWindow - 1e-9) rest_.add(world_->positions());
  fail(std::move(failure));
  for (RunObserver* o : observers_) o->frame(*this);
  return failure_;
}

bool Run::retry() {
  if (!failure_) return false;
  bool untried = untried_;
  if (!retryDefaultStep(path_, scene_, *failure_, untried, threadCount(options_), std::cerr)) return false;
  untried_ = untried;
  restart();
  return true;
}

const std::optional<Failure>& Run::judgeEnd() {
  if (!failure_) fail(endCriteria(*world_, *monitor_, rest_, options_.endVolume, options_.endAtRest));
  return failure_;
}

std::optional<Failure> Run::complete() {
  for (;;) {
    const bool fromStart = pristine_;
    if (fromStart) start();
    while (frame_ < frames_ && !failure_) {
      nextFrame();
      if (interrupted()) return std::nullopt;
    }
    if (!failure_) break;
    if (!fromStart || !retry()) return failure_;
  }
  return judgeEnd();
}

std::optional<Failure> Run::runUntil(double time) {
  for (;;) {
    if (failure_) return failure_;
    const double next = static_cast<double>(frame_ + 1) * frameTime_;
    const bool onFrame = next <= time + 1e-9 * frameTime_;
    if (onFrame) {
      nextFrame();
    } else if (!world_->reached(time)) {
      pristine_ = false;
      fail(advanceTo(*world_, *monitor_, time));
    }
    if (interrupted() || !onFrame) return failure_;
  }
}

std::optional<Failure> Run::step(long count, bool check) {
  if (failure_) return failure_;
  pristine_ = false;
  const double since = monitor_->since();
  for (long i = 0; i < count && world_->stepProblem().empty() && !monitor_->watched() && !interrupted(); ++i) {
    world_->stepToward(std::numeric_limits<double>::infinity());
    if (world_->stepProblem().empty()) monitor_->watchStep(*world_);  // every step, as stepTo
  }
  if (monitor_->watched()) return fail(monitor_->watched());
  if (!world_->stepProblem().empty()) {
    std::optional<Failure> seen = monitor_->check(*world_);  // a blow-up it sees says more
    return fail(seen ? seen : stepFailure(*world_, since));
  }
  while (world_->reached(static_cast<double>(frame_ + 1) * frameTime_)) ++frame_;
  if (check) fail(monitor_->check(*world_));
  return failure_;
}

void Run::setState(std::vector<Vec3> x, std::vector<Vec3> v) {
  world_->setState(std::move(x), std::move(v), world_->time());
  MonitorLimits limits;
  limits.minVolume = options_.minVolume;
  monitor_.emplace(*world_, limits);
  failure_.reset();
  pristine_ = false;
}

void Run::setCriteria(std::optional<double> minVolume, std::optional<double> endVolume,
                      std::optional<bool> endAtRest) {
  RunOptions o = options_;
  if (minVolume) o.minVolume = std::max(o.minVolume, *minVolume);
  if (endVolume) o.endVolume = *endVolume;
  if (endAtRest) o.endAtRest = *endAtRest;
  checkRunOptions(o);
  options_ = std::move(o);
  monitor_->setMinVolume(options_.minVolume);
}

SceneRecord Run::record() const {
  SceneRecord record;
  record.path = path_;
  record.scene = scene_.name;
  record.integrator = std::string(integratorName(scene_.integrator));
  record.dt = scene_.dt;
  record.duration = scene_.duration;
  record.substeps = scene_.substeps;
  record.wall = wallSeconds();
  for (uint32_t b = 0; b < world_->model().bodies.size(); ++b) {
    record.bodies.push_back(bodyResult(*world_, *monitor_, rest_, b));
  }
  if (failure_) {
    record.status = SceneRecord::Status::Failed;
    record.failedBody = failure_->body;
    record.message = failure_->message;
  }
  return record;
}

BodyResult bodyResult(const World& world, const Monitor& monitor, const RestWatch& rest, uint32_t body) {
  const BodyRecord& r = monitor.records()[body];
  const BodyInfo& info = world.model().bodies[body];
  BodyResult result;
  result.name = info.name;
  result.steps = world.stepCount();
  result.time = world.time();
  result.maxStrain = r.maxStrain;
  result.maxPenetration = r.maxPenetration;
  if (info.restVolume > 0.0) {  // an open surface (a cloth) encloses no volume
    result.volumeMin = r.minVolumeRatio;
    result.volumeEnd = r.last.volume / info.restVolume;
  }
  result.kinetic = r.last.kinetic;
  result.gravitational = r.last.gravitational;
  result.elastic = r.last.elastic;
  result.atRest = rest.atRest(info);
  return result;
}

std::optional<Failure> endCriteria(const World& world, const Monitor& monitor, const RestWatch& rest,
                                   double endVolume, bool endAtRest) {
  const std::vector<BodyInfo>& bodies = world.model().bodies;
  for (uint32_t b = 0; b < bodies.size() && endVolume > 0.0; ++b) {
    const BodyInfo& info = bodies[b];
    if (!(info.restVolume > 0.0)) continue;  // an open surface: no volume to keep
    const double ratio = monitor.records()[b].last.volume / info.restVolume;
    if (ratio < endVolume) {
      char what[256];
      std::snprintf(what, sizeof what, "body '%s' ends at %.1f%% of its rest volume, below the required %.1f%%",
                    info.name.c_str(), 100.0 * ratio, 100.0 * endVolume);
      return Failure{b, world.stepCount(), world.time(), what, true};
    }
  }
  for (uint32_t b = 0; b < bodies.size() && endAtRest; ++b) {
    const BodyInfo& info = bodies[b];
    if (rest.atRest(info)) continue;
    const auto [moved, worst] = rest.largestMove(info);
    char what[400];
    std::snprintf(what, sizeof what,
                  "body '%s' is not at rest at the end: in the last %.0f s its vertex %u (of the mesh) moved "
                  "over %.3g m, more than %.3g m (%.1f%% of its size); lengthen the scene or damp the body more "
                  "(strut_decay, hinge_decay, [environment] drag)",
                  info.name.c_str(), RestWatch::kWindow, info.meshVertex(worst), moved,
                  RestWatch::kFraction * info.restSize, 100.0 * RestWatch::kFraction);
    return Failure{b, world.stepCount(), world.time(), what, true};
  }
  return std::nullopt;
}

uint32_t touchingVertices(const World& world, uint32_t body) {
  const BodyInfo& info = world.model().bodies[body];
  uint32_t count = 0;
  for (uint32_t v = info.firstVertex; v < info.firstVertex + info.vertexCount; ++v) count += world.touching(v) ? 1 : 0;
  return count;
}

}  // namespace springy

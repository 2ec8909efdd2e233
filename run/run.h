// springy run: one run of a scene, the one way every front end simulates.
//
// A Run owns what a run is: the scene loaded with the run options (run/load.h), its World, the
// stability monitor, the rest watch of the last second, the frame clock (frame k is the world at
// k / fps; a run checks frames 1 .. frames(), the states a video shows), the time step with its
// retry (a scene that gives no step runs at the advisor's default, and this run is that step's
// try: if it fails, longer counts of substeps are tried and the run starts over at the one that
// passes) and interruption (sim/interrupt.h: the run stops within a step).
//
// Front ends hold one and differ only in what they make of it: check prints its table, render and
// report draw its frames, export writes them, the Python module hands out its state. Outputs
// are observers (RunObserver) of the run's frames: a trace, an export, the report's plots, a
// video's frames. So every output of one command comes from one run, and `check`, `render` and
// the Python module step a scene through the same calls: the same bits.
#pragma once

#include <chrono>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "run/options.h"
#include "run/records.h"
#include "scene/scene.h"
#include "sim/monitor.h"
#include "sim/world.h"

namespace springy {

class Run;

// Sees a run's frames, on the thread that steps the run.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  // The run is at t = 0: first, and again each time it starts over (the default step's retry):
  // an output starts again, dropping what the failed try gave it.
  virtual void started(const Run& run) { (void)run; }
  // Frame run.frame() was reached and checked. Also the frame a run failed at (run.failure()
  // set), so that a plot shows where it stopped; no frame follows that one.
  virtual void frame(const Run& run) = 0;
};

class Run {
 public:
  // Loads the scene as `springy check` loads it (run/load.h loadSceneWith, the advisor's notes on
  // std::cerr) and makes its world. `edit`, when given, changes the scene before the world is made
  // (render's --width, --fps). Throws springy::Error.
  explicit Run(std::string path, RunOptions options = {}, const std::function<void(SceneDesc&)>& edit = {});
  Run(const Run&) = delete;  // observers and views keep its address
  Run& operator=(const Run&) = delete;

  const std::string& path() const { return path_; }
  const RunOptions& options() const { return options_; }
  const SceneDesc& scene() const { return scene_; }
  World& world() { return *world_; }
  const World& world() const { return *world_; }
  const Monitor& monitor() const { return *monitor_; }
  const RestWatch& rest() const { return rest_; }
  double frameTime() const { return frameTime_; }  // 1 / fps [s]
  long frames() const { return frames_; }          // the frames a whole run checks
  long frame() const { return frame_; }            // the frames reached so far (0 at the start)
  // The step is the advisor's default, not yet through a whole run: this run is its try.
  bool untried() const { return untried_; }
  // At the scene's start as loaded (no frame reached, no state set by hand).
  bool pristine() const { return pristine_; }
  // What stopped the run: the monitor's failure, or a criterion's (Failure::criterion). Once set,
  // the run steps no further (its state is what the monitor refused).
  const std::optional<Failure>& failure() const { return failure_; }
  // Wall time since the run last started [s].
  double wallSeconds() const;

  // The observers, in the order they see each frame (not owned; they outlive the run's use).
  void observe(RunObserver& observer) { observers_.push_back(&observer); }

  // Runs on from where the run is to its last frame, frame by frame; the observers see each.
  // When the run was pristine and fails as the default step's try, the advisor tries longer steps
  // and the run starts over at the one that passes (observers see started() again). Then the
  // options' criteria (end volume, at rest). Returns the failure, if any; stops early, with none,
  // when interrupted() (the caller sees it). Throws springy::Error when no step passes.
  std::optional<Failure> complete();

  // The parts of complete(), for a front end that runs the frames on its own thread (render's
  // pipeline): notify the observers that the run starts (call before the first frame), and
  // advance one frame (the observers see it).
  void start();
  const std::optional<Failure>& nextFrame();
  // After a failed run from the start: the default step's retry (retryDefaultStep). True when it
  // found a step that passes: the run is back at t = 0 at that step (the caller runs it again).
  // False when the failure is the run's to report. Throws springy::Error when no step passes.
  bool retry();
  // The options' end criteria on a run that reached its end: sets failure() when one fails.
  const std::optional<Failure>& judgeEnd();

  // Runs frame by frame up to `time`, then to `time` itself (a still between frames, Python's
  // run(until)). Returns the failure, if any; nothing when interrupted.
  std::optional<Failure> runUntil(double time);
  // `count` steps (the adaptive step: accepted steps), then the monitor's check when `check`. The
  // frames passed are counted (the rest watch is fed only by runUntil and complete).
  std::optional<Failure> step(long count, bool check = true);

  // Replaces the state (Python's setters): the monitor watches anew from here (energy put in by
  // hand is no instability), and a failure is forgotten.
  void setState(std::vector<Vec3> x, std::vector<Vec3> v);
  // Python's check(min_volume=..., ...): raises the monitor's volume limit to minVolume (from the
  // next check on) and sets the end criteria given.
  void setCriteria(std::optional<double> minVolume, std::optional<double> endVolume, std::optional<bool> endAtRest);

  // The run's record, as `check --json` writes it: status, the failure, every body's result.
  SceneRecord record() const;

  // A retry (retry()) starts a new world; with this set, the worlds it replaces are kept (with
  // their buffers) until the run goes, instead of freed first: Python's zero-copy state views
  // point into a world's buffers, and one taken before check() started over must not point at
  // freed memory (it shows the state the old world had). Costs a world per retry, so only the
  // module asks for it.
  void keepReplacedWorlds() { keepReplaced_ = true; }

 private:
  void restart();  // a new world at t = 0, at the scene's step
  const std::optional<Failure>& fail(std::optional<Failure> failure);

  std::string path_;
  RunOptions options_;
  SceneDesc scene_;
  bool untried_ = false;
  double frameTime_ = 0.0;
  long frames_ = 0;
  std::optional<World> world_;
  bool keepReplaced_ = false;
  std::deque<World> replaced_;  // keepReplacedWorlds(): the worlds a retry replaced
  std::optional<Monitor> monitor_;
  RestWatch rest_;
  long frame_ = 0;
  bool pristine_ = true;
  std::optional<Failure> failure_;
  std::chrono::steady_clock::time_point startedAt_;
  std::vector<RunObserver*> observers_;
};

// One body's results after a run (check's table, --json, the Python module's sim.check()): the
// monitor's extremes and last measures, and whether `rest` saw it at rest.
BodyResult bodyResult(const World& world, const Monitor& monitor, const RestWatch& rest, uint32_t body);

// How many of the body's vertices touch a collider or a body now (World::touching).
uint32_t touchingVertices(const World& world, uint32_t body);

// check's criteria at the end of a run that passed the monitor: endVolume (a body ending below
// that fraction of its rest volume; 0: not checked) and endAtRest (every body at rest over the
// frames `rest` watched). The first failure (Failure::criterion set), if any.
std::optional<Failure> endCriteria(const World& world, const Monitor& monitor, const RestWatch& rest,
                                   double endVolume, bool endAtRest);

}  // namespace springy

// springy: what moves on its own in a run (sim/motion.h), as a World drives it: the colliders
// that move, whose poses over each step the collide stage reads; the pins that follow a track
// or are released at a time; and the times the adaptive step lands on (their keyframes and
// releases, and the soft attachments' releases), where a velocity or an acceleration jumps.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/colliders.h"
#include "sim/model.h"
#include "sim/state.h"

namespace springy {

class Drivers {
 public:
  explicit Drivers(const Model& model);  // reads `model`, which must outlive this object and not move

  bool movingColliders() const { return movingColliders_; }
  // The times a step lands on, ascending.
  const std::vector<double>& kinks() const { return kinks_; }
  // The moving colliders' poses over [t0, t1], the step being taken (for poses()).
  void over(double t0, double t1) {
    if (movingColliders_) model_->colliders.posesOver(t0, t1, poses_);
  }
  // Their poses over the step, or null when none moves (the colliders' still fast path).
  const ColliderPoses* poses() const { return movingColliders_ ? &poses_ : nullptr; }
  // How many pin tracks the model has (State::released has one flag each).
  std::size_t pinTracks() const { return tracked_.size(); }
  // Puts the tracked pins where their motion has them at state.time, with its velocity, and frees
  // those due (State::invMass gets their 1 / m; they go on at the velocity the motion gave them).
  // True when it changed the state.
  bool follow(State& state) const;

 private:
  // Pins that move or are released (Model::pinTracks): their vertices and rest positions.
  struct TrackedPins {
    const Model::PinTrack* track = nullptr;
    std::vector<uint32_t> vertices;
    std::vector<Vec3> rest;
  };
  const Model* model_;
  bool movingColliders_ = false;
  ColliderPoses poses_;
  std::vector<double> kinks_;
  std::vector<TrackedPins> tracked_;
};

}  // namespace springy

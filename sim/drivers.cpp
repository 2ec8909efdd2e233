#include "sim/drivers.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace springy {

Drivers::Drivers(const Model& model) : model_(&model), movingColliders_(model.colliders.moving()) {
  if (movingColliders_) kinks_ = model.colliders.kinks();
  // Vertices held hard to a collider ([[attach]]) follow it, not their body's pin track.
  std::set<uint32_t> attachedHard;
  for (const Model::PinTrack& track : model.pinTracks) attachedHard.insert(track.vertices.begin(), track.vertices.end());
  for (const Model::PinTrack& track : model.pinTracks) {
    TrackedPins& t = tracked_.emplace_back();
    t.track = &track;
    if (track.vertices.empty()) {
      for (uint32_t i : model.pinned) {
        if (model.body[i] == track.body && !attachedHard.count(i)) t.vertices.push_back(i);
      }
      for (uint32_t i : t.vertices) t.rest.push_back(model.restPosition[i]);
    } else {  // attached to a collider: kept where they are relative to it
      t.vertices = track.vertices;
      const Pose start = track.motion.pose(0.0);
      for (uint32_t i : t.vertices) {
        t.rest.push_back(track.motion.moves() ? start.inverse(model.restPosition[i]) : model.restPosition[i]);
      }
    }
    for (double k : track.motion.kinks()) kinks_.push_back(k);
    if (std::isfinite(track.release)) kinks_.push_back(track.release);
  }
  for (const Model::Attachment& a : model.attachments) {
    if (std::isfinite(a.release)) kinks_.push_back(a.release);
  }
  std::sort(kinks_.begin(), kinks_.end());
  kinks_.erase(std::unique(kinks_.begin(), kinks_.end()), kinks_.end());
}

bool Drivers::follow(State& state) const {
  bool changed = false;
  for (std::size_t p = 0; p < tracked_.size(); ++p) {
    const TrackedPins& t = tracked_[p];
    if (state.released[p]) continue;
    const Model::PinTrack& track = *t.track;
    if (state.time >= track.release) {
      for (uint32_t i : t.vertices) state.invMass[i] = 1.0 / model_->mass[i];
      state.released[p] = 1;
      changed = true;
      continue;
    }
    if (!track.motion.moves()) continue;
    const Pose pose = track.motion.pose(state.time);
    for (std::size_t k = 0; k < t.vertices.size(); ++k) {
      const uint32_t i = t.vertices[k];
      state.x[i] = pose.apply(t.rest[k]);
      state.v[i] = track.motion.velocityAt(state.x[i], state.time);
    }
    changed = true;
  }
  return changed;
}

}  // namespace springy

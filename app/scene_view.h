// springy app: the bridge between a simulated world and the renderer. It turns the scene's
// bodies, colliders and props into the renderer's plain draw data once, and streams vertex
// positions each frame. sim/ and render/ know nothing of each other; only this file knows both.
#pragma once

#include <string>
#include <vector>

#include "render/image.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace springy {

// What a frame needs from one simulated instant, copied out of the World so that simulation and
// drawing can run on different threads (the World is not thread-safe). Buffers are reused:
// takeSnapshot only allocates when the vertex count grows.
struct FrameSnapshot {
  double time = 0.0;
  double dt = 0.0;
  std::vector<float> positions;  // x, y, z per vertex of every body, bodies in model order
  std::vector<uint8_t> resting;  // per vertex, the same order: 1 if it rests on a static collider
};
void takeSnapshot(const World& world, FrameSnapshot& snapshot);

class SceneView {
 public:
  // Reads the world's model (topology, colliders) once; later calls never touch `world`.
  SceneView(const SceneDesc& scene, const World& world, render::RenderSettings settings);
  // Uploads the snapshot's positions and overlay text, draws the frame (same as draw(world) at
  // the instant the snapshot was taken).
  void draw(const FrameSnapshot& snapshot);
  void draw(const World& world);
  render::Renderer& renderer() { return renderer_; }

 private:
  const SceneDesc& scene_;
  render::Renderer renderer_;
  std::vector<render::MeshId> bodyMeshes_;
  std::vector<uint32_t> bodyVertexCounts_;
  // Per body simulated through a proxy: the user's mesh bound to it (corners as the body's
  // model-local vertex indices), drawn instead of the proxy; empty for the others.
  std::vector<Embedding> drawBindings_;
  // Colliders that move on their own: drawn where their motion has them at the frame's time.
  struct Moving {
    render::MeshId id;
    std::size_t index;  // into the scene's planes or triangle colliders
  };
  std::vector<Moving> movingPlanes_, movingMeshes_, movingProps_;
  std::vector<std::vector<float>> propRest_;  // per moving prop: its mesh's positions at rest
  void placeMovingColliders(double t);
  // The constructor's steps.
  void addBodies(const World& world);
  void addColliders(Bounds& all);
  void placeCamera(const Bounds& all);
  std::vector<float> placed_;  // scratch: a drawn mesh's positions
  std::string integrator_;
  FrameSnapshot scratch_;  // for draw(world)
};

// Throws springy::Error naming the scene file and the keys when the scene's camera cannot look
// anywhere ([render.camera] position == target). Called before any output is created.
void checkCamera(const SceneDesc& scene);

// Render settings from a scene's [render] table.
render::RenderSettings renderSettingsOf(const SceneDesc& scene);

// The stills of a contact sheet when none are asked for (`springy frames`, the report): eight
// evenly spaced over the run, its start and its end included.
std::vector<double> sheetTimes(double duration);
// A contact sheet's layout for that many stills: at most four columns.
render::ContactSheetOptions sheetOptions(std::size_t stills);

}  // namespace springy

// springy app: the bridge between a simulated world and the renderer. It turns the scene's
// bodies, colliders and props into the renderer's plain draw data once, and streams vertex
// positions each frame. sim/ and render/ know nothing of each other; only this file knows both.
#pragma once

#include <string>
#include <vector>

#include "render/renderer.hpp"
#include "sim/scene.h"

namespace springy {

class SceneView {
 public:
  SceneView(const SceneDesc& scene, const World& world, render::RenderSettings settings);
  // Uploads the world's current positions and overlay text, draws the frame.
  void draw(const World& world);
  render::Renderer& renderer() { return renderer_; }

 private:
  const SceneDesc& scene_;
  render::Renderer renderer_;
  std::vector<render::MeshId> bodyMeshes_;
  std::vector<float> positions_;  // scratch, one body at a time
};

// Render settings from a scene's [render] table.
render::RenderSettings renderSettingsOf(const SceneDesc& scene);

}  // namespace springy

// Why: the shadow map's placement is geometry, not GL. One directional light gets an orthographic
// frustum around the shadow casters, snapped to whole texels so that shadows do not shimmer as
// the casters move, and a map resolution fitted to how large the casters appear on screen
// (fewer depth texels to rasterise when they are small or far). A ground then needs the shadow
// taps only inside the screen rectangle the map covers (shadowFootprint). The renderer does the
// GL work; these functions only compute. Internal to render/.
#pragma once
#include <glm/glm.hpp>
#include <limits>
#include <optional>
#include <span>

#include "render/camera.h"
#include "render/renderer.h"

namespace springy::render {

// An axis-aligned box; empty (lo > hi) until a point is added.
struct Bounds {
  glm::vec3 lo{std::numeric_limits<float>::max()};
  glm::vec3 hi{std::numeric_limits<float>::lowest()};
  bool empty() const { return lo.x > hi.x; }
  void add(glm::vec3 p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void add(const Bounds& b) {
    if (!b.empty()) add(b.lo), add(b.hi);
  }
};

struct ShadowFit {
  glm::mat4 lightViewProj{1.0f};  // world -> the shadow map's clip space
  int mapSize = 0;                // shadow map texels per side (a power of two, or shadowMapSize)
  float texelWorld = 0.0f;        // one texel's size in world units [m]
};

// The light frustum around `casters` (not empty) for a light travelling along lightDirection,
// and the map size: with settings.fitShadowMap the smallest power of two in
// 256..settings.shadowMapSize whose texels cover at most one pixel (of settings.height) where
// the casters are nearest `camera`; otherwise settings.shadowMapSize.
ShadowFit fitShadowMap(const Bounds& casters, glm::vec3 lightDirection, const Camera& camera,
                       const RenderSettings& settings);

// The screen rectangle (x, y, width, height in pixels, rows bottom-up as GL's scissor; empty
// when off screen) around the points projected by viewProj, widened by `margin` pixels; none
// (unbounded) when a point lies behind the camera.
std::optional<glm::ivec4> screenRect(std::span<const glm::vec3> points, const glm::mat4& viewProj, int width,
                                     int height, float margin);

// The screen rectangle (x, y, width, height in pixels, rows bottom-up as GL's scissor; empty
// when off screen) that holds every pixel of the plane through planePoint spanned by planeU and
// planeV that the shadow map covers: the light frustum's sides followed along the light onto
// the plane, projected by viewProj. None (shade all of the plane with shadows) when the light
// grazes the plane or a corner lies behind the camera.
std::optional<glm::ivec4> shadowFootprint(glm::vec3 planePoint, glm::vec3 planeU, glm::vec3 planeV,
                                          glm::vec3 lightDirection, const glm::mat4& lightViewProj,
                                          const glm::mat4& viewProj, int width, int height);

}  // namespace springy::render

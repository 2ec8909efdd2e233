// Why: one place for the camera maths (view and projection matrices) so that the renderer and
// anything that needs to know where a point lands on screen (tests, the app) agree exactly.
#pragma once
#include <glm/glm.hpp>

namespace springy::render {

// A perspective camera looking from `position` at `target`.
struct Camera {
  glm::vec3 position{0.0f, 2.0f, 6.0f};
  glm::vec3 target{0.0f, 0.5f, 0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fovYDeg = 45.0f;   // vertical field of view, degrees
  float nearPlane = 0.05f;
  float farPlane = 500.0f;

  // glm::lookAt(position, target, up); when the view is (nearly) parallel to `up` another up is
  // chosen (see camera.cpp). Throws RenderError when position == target.
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;   // glm::perspective, aspect = width / height
  glm::mat4 viewProjection(float aspect) const { return projection(aspect) * view(); }

  // A camera `distance` away from `target`, rotated yawDeg about +up (0 = looking along -Z from
  // +Z) and raised pitchDeg above the horizontal. `up` must be +Y for this helper.
  static Camera orbit(glm::vec3 target, float distance, float yawDeg, float pitchDeg,
                      float fovYDeg = 45.0f);
};

// Where a world point lands in an image of width x height: x right, y DOWN (row index, top-down
// like readPixels), in pixels; z is the NDC depth (-1 near .. 1 far). Behind the camera: w <= 0,
// returned as z > 1.
glm::vec3 projectToPixel(const Camera& camera, glm::vec3 world, int width, int height);

// A camera that shows the whole box [lo, hi] for a frame of the given aspect (width / height),
// seen from the orbit direction yawDeg/pitchDeg, with `margin` (fraction) of space around it.
Camera frameBounds(glm::vec3 lo, glm::vec3 hi, float aspect, float fovYDeg = 40.0f,
                   float yawDeg = 30.0f, float pitchDeg = 20.0f, float margin = 0.1f);

}  // namespace springy::render

#include "render/camera.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "render/error.h"

namespace springy::render {

glm::mat4 Camera::view() const {
  const glm::vec3 forward = target - position;
  const float length = glm::length(forward), upLength = glm::length(up);
  // lookAt needs a direction and an up vector not parallel to it: with position == target it
  // divides by zero, and looking straight along up (a camera right above its target) it builds a
  // degenerate basis, NaNs, and the frame shows only sky.
  if (!(length > 0.0f) || !(upLength > 0.0f))
    throw RenderError("camera: position (" + std::to_string(position.x) + ", " + std::to_string(position.y) +
                      ", " + std::to_string(position.z) + ") and target must differ, and up must not be zero");
  glm::vec3 u = up / upLength;
  const float along = glm::dot(forward / length, u);
  if (std::abs(along) > 0.999999f) {  // within 0.08 degrees
    // (Nearly) vertical view: the image's up becomes the horizontal direction the camera would
    // face had it pitched down (or up) from a level view along -Z, so looking down from above,
    // -Z is at the top of the frame, continuous with a camera tilting down towards the target.
    const glm::vec3 side = std::abs(u.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 0.0f, 1.0f);
    u = glm::normalize(glm::cross(u, side)) * (along < 0.0f ? 1.0f : -1.0f);
  }
  return glm::lookAt(position, target, u);
}

glm::mat4 Camera::projection(float aspect) const {
  return glm::perspective(glm::radians(fovYDeg), aspect, nearPlane, farPlane);
}

Camera Camera::orbit(glm::vec3 target, float distance, float yawDeg, float pitchDeg,
                     float fovYDeg) {
  const float yaw = glm::radians(yawDeg), pitch = glm::radians(pitchDeg);
  const glm::vec3 dir{std::sin(yaw) * std::cos(pitch), std::sin(pitch),
                      std::cos(yaw) * std::cos(pitch)};
  Camera c;
  c.target = target;
  c.position = target + distance * dir;
  c.up = {0.0f, 1.0f, 0.0f};
  c.fovYDeg = fovYDeg;
  c.nearPlane = std::max(1e-3f, distance * 0.01f);
  c.farPlane = std::max(100.0f, distance * 100.0f);
  return c;
}

glm::vec3 projectToPixel(const Camera& camera, glm::vec3 world, int width, int height) {
  const float aspect = static_cast<float>(width) / static_cast<float>(height);
  const glm::vec4 clip = camera.viewProjection(aspect) * glm::vec4(world, 1.0f);
  if (clip.w <= 0.0f) return {0.0f, 0.0f, 2.0f};
  const glm::vec3 ndc = glm::vec3(clip) / clip.w;
  return {(ndc.x * 0.5f + 0.5f) * static_cast<float>(width),
          (0.5f - ndc.y * 0.5f) * static_cast<float>(height), ndc.z};
}

Camera frameBounds(glm::vec3 lo, glm::vec3 hi, float aspect, float fovYDeg, float yawDeg,
                   float pitchDeg, float margin) {
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * glm::length(hi - lo), 1e-3f) * (1.0f + margin);
  // The bounding sphere must fit both the vertical and the horizontal field of view.
  const float halfV = glm::radians(fovYDeg) * 0.5f;
  const float halfH = std::atan(std::tan(halfV) * aspect);
  const float distance = radius / std::sin(std::min(halfV, halfH));
  Camera c = Camera::orbit(centre, distance, yawDeg, pitchDeg, fovYDeg);
  c.nearPlane = std::max(1e-3f, (distance - radius) * 0.5f);
  c.farPlane = distance + radius * 50.0f;
  return c;
}

}  // namespace springy::render

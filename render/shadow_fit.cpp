#include "render/shadow_fit.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace springy::render {

namespace {

// Shadow map texels needed for light-space extent `size` (world units): at the casters'
// nearest point to the camera, a texel should cover at most one pixel (the PCF taps blur over
// 4 texels anyway; the bounds' corners overestimate a round caster). A power of two in
// 256..shadowMapSize; shadowMapSize when fitting is off.
int fittedShadowSize(const Bounds& b, float size, const Camera& camera, const RenderSettings& settings) {
  if (!settings.fitShadowMap) return settings.shadowMapSize;
  const glm::vec3 centre = 0.5f * (b.lo + b.hi);
  const float radius = 0.5f * glm::length(b.hi - b.lo);
  const float distance = std::max(glm::length(centre - camera.position) - radius, camera.nearPlane);
  const float pixelsPerUnit = static_cast<float>(settings.height) /
                              (2.0f * distance * std::tan(glm::radians(0.5f * camera.fovYDeg)));
  const float texels = size * pixelsPerUnit;
  int n = 256;
  while (n < settings.shadowMapSize && static_cast<float>(n) < texels) n *= 2;
  return std::min(n, settings.shadowMapSize);
}

}  // namespace

ShadowFit fitShadowMap(const Bounds& b, glm::vec3 lightDirection, const Camera& camera,
                       const RenderSettings& settings) {
  const glm::vec3 d = glm::normalize(lightDirection);
  const float radius = std::max(0.5f * glm::length(b.hi - b.lo), 1e-3f);
  const glm::vec3 up = std::abs(d.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
  // View matrix at the origin-aligned light basis (translation-free, so snapping is stable).
  const glm::mat4 view = glm::lookAt(glm::vec3(0.0f), d, up);
  Bounds ls;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
    ls.add(glm::vec3(view * glm::vec4(corner, 1.0f)));
  }
  const float pad = 0.05f * radius + 1e-3f;
  float size = std::max(ls.hi.x - ls.lo.x, ls.hi.y - ls.lo.y) + 2.0f * pad;
  size = std::exp2(std::ceil(std::log2(size) * 8.0f) / 8.0f);  // 1/8-octave steps
  ShadowFit fit;
  fit.mapSize = fittedShadowSize(b, size, camera, settings);
  // Snap the frustum's centre to whole texels.
  const float texel = size / static_cast<float>(fit.mapSize);
  glm::vec2 mid(0.5f * (ls.lo.x + ls.hi.x), 0.5f * (ls.lo.y + ls.hi.y));
  mid = glm::floor(mid / texel) * texel;
  fit.texelWorld = texel;
  const float nearZ = -ls.hi.z - pad, farZ = -ls.lo.z + pad;
  const glm::mat4 proj = glm::ortho(mid.x - 0.5f * size, mid.x + 0.5f * size, mid.y - 0.5f * size,
                                    mid.y + 0.5f * size, nearZ, farZ);
  fit.lightViewProj = proj * view;
  return fit;
}

std::optional<glm::ivec4> screenRect(std::span<const glm::vec3> points, const glm::mat4& viewProj, int width,
                                     int height, float margin) {
  glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const glm::vec3& p : points) {
    const glm::vec4 clip = viewProj * glm::vec4(p, 1.0f);
    if (!(clip.w > 1e-4f)) return std::nullopt;
    const glm::vec2 ndc = glm::vec2(clip) / clip.w;
    lo = glm::min(lo, ndc);
    hi = glm::max(hi, ndc);
  }
  const glm::vec2 size(static_cast<float>(width), static_cast<float>(height));
  const glm::vec2 pLo = glm::clamp((lo * 0.5f + 0.5f) * size - margin, glm::vec2(0.0f), size);
  const glm::vec2 pHi = glm::clamp((hi * 0.5f + 0.5f) * size + margin, glm::vec2(0.0f), size);
  const glm::ivec2 a(glm::floor(pLo)), b(glm::ceil(pHi));
  return glm::ivec4(a.x, a.y, std::max(b.x - a.x, 0), std::max(b.y - a.y, 0));
}

std::optional<glm::ivec4> shadowFootprint(glm::vec3 planePoint, glm::vec3 planeU, glm::vec3 planeV,
                                          glm::vec3 lightDirection, const glm::mat4& lightViewProj,
                                          const glm::mat4& viewProj, int width, int height) {
  const glm::vec3 n = glm::normalize(glm::cross(planeU, planeV));
  const glm::vec3 d = glm::normalize(lightDirection);
  const float along = glm::dot(d, n);
  if (std::abs(along) < 0.05f) return std::nullopt;
  const glm::mat4 toWorld = glm::inverse(lightViewProj);
  glm::vec3 onPlane[4];
  for (int k = 0; k < 4; ++k) {
    const glm::vec4 w = toWorld * glm::vec4((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f, -1.0f, 1.0f);
    const glm::vec3 c = glm::vec3(w) / w.w;
    onPlane[k] = c + d * (glm::dot(planePoint - c, n) / along);
  }
  // Widened by 4 pixels: the normal offset and the filter taps reach a little past the sides.
  return screenRect(onPlane, viewProj, width, height, 4.0f);
}

}  // namespace springy::render

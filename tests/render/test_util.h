// Why: pixel access helpers shared by the render tests (images are RGBA8, rows top-down).
#pragma once
#include <cstdint>
#include <cstdlib>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "render/image.h"
#include "render/renderer.h"

namespace springy::render::test {

inline glm::vec3 pixel(const std::vector<std::uint8_t>& rgba, int width, int x, int y) {
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                         static_cast<std::size_t>(x)) * 4;
  return {static_cast<float>(rgba[i]), static_cast<float>(rgba[i + 1]),
          static_cast<float>(rgba[i + 2])};
}

// Mean RGB (0..255) over the (2r+1)^2 square centred on (cx, cy), clipped to the image.
inline glm::vec3 regionMean(const std::vector<std::uint8_t>& rgba, int width, int height, int cx,
                            int cy, int r) {
  glm::vec3 sum(0.0f);
  int n = 0;
  for (int y = cy - r; y <= cy + r; ++y)
    for (int x = cx - r; x <= cx + r; ++x) {
      if (x < 0 || y < 0 || x >= width || y >= height) continue;
      sum += pixel(rgba, width, x, y);
      ++n;
    }
  return n ? sum / static_cast<float>(n) : sum;
}

// Small frames for fast tests: w x h, anti-aliasing off unless asked, a 1024 shadow map.
inline RenderSettings small(int w = 64, int h = 48, bool aa = false) {
  RenderSettings s;
  s.width = w;
  s.height = h;
  s.antiAlias = aa;
  s.shadowMapSize = 1024;
  return s;
}

// Optional: SPRINGY_RENDER_DUMP=dir writes the test frames as PNGs for a human to look at.
inline void dump(const Image& img, const std::string& name) {
  if (const char* dir = std::getenv("SPRINGY_RENDER_DUMP")) writePng(std::string(dir) + "/" + name, img);
}

inline float luminance(glm::vec3 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

}  // namespace springy::render::test

// Why: overlay lines on frames and labels on contact sheets need text without a GUI toolkit.
// Font rasterises a TrueType font with stb_truetype and draws UTF-8 strings onto plain RGBA8
// images on the CPU; the renderer uploads the result as a texture.
#pragma once
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace springy::render {

inline constexpr const char* kDefaultFontPath = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

// An RGBA8 image, rows top-down, 4 bytes per pixel, no padding.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;
};

class Font {
public:
  // Loads the font file; throws RenderError naming the path if it cannot be read or parsed.
  // pixelHeight: the line's ascent-to-descent height in pixels.
  explicit Font(const std::string& path = kDefaultFontPath, float pixelHeight = 18.0f);
  ~Font();
  Font(const Font&) = delete;
  Font& operator=(const Font&) = delete;

  float pixelHeight() const { return pixelHeight_; }
  int lineHeight() const;  // baseline-to-baseline distance, pixels
  int ascent() const;      // pixels above the baseline
  int textWidth(std::string_view utf8) const;

  // Alpha-blends the text in `colour` (0..1 RGB, `alpha` coverage scale) onto the image, the top
  // of the line at row `top`, starting at column `left`. Clipped to the image.
  void draw(Image& image, int left, int top, std::string_view utf8, glm::vec3 colour,
            float alpha = 1.0f) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  float pixelHeight_;
};

// Blends a solid rectangle onto the image (clipped).
void fillRect(Image& image, int x, int y, int w, int h, glm::vec3 colour, float alpha);

}  // namespace springy::render

#include "render/text.h"

#include <stb/stb_truetype.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

#include "render/error.h"

namespace springy::render {

struct Font::Impl {
  std::vector<unsigned char> data;
  stbtt_fontinfo info{};
  float scale = 1.0f;
  int ascent = 0, descent = 0, lineGap = 0;  // font units
  mutable std::vector<unsigned char> glyph;   // scratch bitmap
};

namespace {
// Minimal UTF-8 decoder; invalid bytes decode as '?'.
std::vector<int> decodeUtf8(std::string_view s) {
  std::vector<int> out;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    int cp = '?';
    std::size_t len = 1;
    if (c < 0x80) cp = c;
    else if ((c >> 5) == 0x6) len = 2, cp = c & 0x1F;
    else if ((c >> 4) == 0xE) len = 3, cp = c & 0x0F;
    else if ((c >> 3) == 0x1E) len = 4, cp = c & 0x07;
    if (len > 1) {
      if (i + len > s.size()) { out.push_back('?'); break; }
      for (std::size_t k = 1; k < len; ++k)
        cp = (cp << 6) | (static_cast<unsigned char>(s[i + k]) & 0x3F);
    }
    out.push_back(cp);
    i += len;
  }
  return out;
}

std::uint8_t blend(std::uint8_t dst, float src, float a) {
  const float v = static_cast<float>(dst) * (1.0f - a) + src * 255.0f * a;
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}

void blendPixel(Image& img, int x, int y, glm::vec3 colour, float a) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height || a <= 0.0f) return;
  std::uint8_t* p = img.rgba.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                                       static_cast<std::size_t>(x)) * 4;
  p[0] = blend(p[0], colour.r, a);
  p[1] = blend(p[1], colour.g, a);
  p[2] = blend(p[2], colour.b, a);
  // Alpha: "over" compositing, so text on a transparent overlay image stays visible.
  const float da = static_cast<float>(p[3]) / 255.0f;
  p[3] = static_cast<std::uint8_t>(std::lround((a + da * (1.0f - a)) * 255.0f));
}
}  // namespace

Font::Font(const std::string& path, float pixelHeight)
    : impl_(std::make_unique<Impl>()), pixelHeight_(pixelHeight) {
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw RenderError("Font: cannot open font file '" + path + "'");
    impl_->data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (impl_->data.empty() ||
        !stbtt_InitFont(&impl_->info, impl_->data.data(),
                        stbtt_GetFontOffsetForIndex(impl_->data.data(), 0)))
      throw RenderError("Font: '" + path + "' is not a TrueType font");
    impl_->scale = stbtt_ScaleForPixelHeight(&impl_->info, pixelHeight);
    stbtt_GetFontVMetrics(&impl_->info, &impl_->ascent, &impl_->descent, &impl_->lineGap);
  }
}

Font::~Font() = default;

int Font::ascent() const {
  return static_cast<int>(std::ceil(static_cast<float>(impl_->ascent) * impl_->scale));
}

int Font::lineHeight() const {
  return static_cast<int>(std::ceil(
      static_cast<float>(impl_->ascent - impl_->descent + impl_->lineGap) * impl_->scale));
}

int Font::textWidth(std::string_view utf8) const {
  const std::vector<int> cps = decodeUtf8(utf8);
  float x = 0.0f;
  for (std::size_t i = 0; i < cps.size(); ++i) {
    int advance = 0, lsb = 0;
    stbtt_GetCodepointHMetrics(&impl_->info, cps[i], &advance, &lsb);
    x += static_cast<float>(advance) * impl_->scale;
    if (i + 1 < cps.size())
      x += impl_->scale *
           static_cast<float>(stbtt_GetCodepointKernAdvance(&impl_->info, cps[i], cps[i + 1]));
  }
  return static_cast<int>(std::ceil(x));
}

void Font::draw(Image& image, int left, int top, std::string_view utf8, glm::vec3 colour,
                float alpha) const {
  const std::vector<int> cps = decodeUtf8(utf8);
  const float baseline = static_cast<float>(top + ascent());
  float x = static_cast<float>(left);
  for (std::size_t i = 0; i < cps.size(); ++i) {
    const float xFloor = std::floor(x);
    const float shift = x - xFloor;
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    stbtt_GetCodepointBitmapBoxSubpixel(&impl_->info, cps[i], impl_->scale, impl_->scale, shift,
                                        0.0f, &x0, &y0, &x1, &y1);
    const int gw = x1 - x0, gh = y1 - y0;
    if (gw > 0 && gh > 0) {
      impl_->glyph.assign(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh), 0);
      stbtt_MakeCodepointBitmapSubpixel(&impl_->info, impl_->glyph.data(), gw, gh, gw,
                                        impl_->scale, impl_->scale, shift, 0.0f, cps[i]);
      const int ox = static_cast<int>(xFloor) + x0;
      const int oy = static_cast<int>(baseline) + y0;
      for (int gy = 0; gy < gh; ++gy)
        for (int gx = 0; gx < gw; ++gx) {
          const float cov =
              static_cast<float>(impl_->glyph[static_cast<std::size_t>(gy * gw + gx)]) / 255.0f;
          blendPixel(image, ox + gx, oy + gy, colour, cov * alpha);
        }
    }
    int advance = 0, lsb = 0;
    stbtt_GetCodepointHMetrics(&impl_->info, cps[i], &advance, &lsb);
    x += static_cast<float>(advance) * impl_->scale;
    if (i + 1 < cps.size())
      x += impl_->scale *
           static_cast<float>(stbtt_GetCodepointKernAdvance(&impl_->info, cps[i], cps[i + 1]));
  }
}

void fillRect(Image& image, int x, int y, int w, int h, glm::vec3 colour, float alpha) {
  for (int yy = std::max(0, y); yy < std::min(image.height, y + h); ++yy)
    for (int xx = std::max(0, x); xx < std::min(image.width, x + w); ++xx)
      blendPixel(image, xx, yy, colour, alpha);
}

}  // namespace springy::render

// Why: still frames and contact sheets are written as PNG (stb_image_write) and read back in
// tests (stb_image). All images are RGBA8 with rows TOP-DOWN, as Renderer::readPixels returns.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "render/text.h"

namespace springy::render {

// What springy's own images and videos carry, so that a later run may replace a file it named
// itself (SCENE.mp4, SCENE_tT.png) only when springy wrote it (app/atomic_file.h
// refuseUnlessMarked): a PNG's tEXt chunk "Software" right after its header, an MP4's comment
// (in its index, which +faststart puts first). Within the first kMarkSearchBytes of the file.
inline constexpr std::string_view kSpringyMark = "made with springy";
inline constexpr std::size_t kMarkSearchBytes = std::size_t{8} << 20;

// An RGBA8 top-down image (rgba.size() == width*height*4) as the bytes of a PNG file, for
// writers that check every write themselves (the app's AtomicFile). Throws RenderError.
std::vector<std::uint8_t> encodePng(int width, int height, std::span<const std::uint8_t> rgba);
inline std::vector<std::uint8_t> encodePng(const Image& image) {
  return encodePng(image.width, image.height, image.rgba);
}
// Writes an RGBA8 top-down image (rgba.size() == width*height*4). Throws RenderError naming the
// path and the reason (strerror) when any write or the close fails (a full disk). Writes exactly
// `path` (no temp file; a failure may leave a partial file).
void writePng(const std::string& path, int width, int height, std::span<const std::uint8_t> rgba);
inline void writePng(const std::string& path, const Image& image) {
  writePng(path, image.width, image.height, image.rgba);
}
// Reads any PNG (or baseline JPEG) as RGBA8 top-down. Throws RenderError naming the path on failure.
Image readPng(const std::string& path);

struct ContactSheetOptions {
  int columns = 4;              // images per row (rows follow from the image count)
  int padding = 8;              // pixels between cells and around the sheet
  float labelPixelHeight = 18;  // label font size; label strip is drawn under each image
  std::uint8_t background[3] = {24, 24, 28};
  std::string fontPath = kDefaultFontPath;
};

// Composes images into a grid, each cell labelled underneath (e.g. "t = 1.50 s"). Images may
// differ in size; cells take the largest size
// (widened to fit the widest label). labels.size() must be 0 or images.size().
Image makeContactSheet(const std::vector<Image>& images, const std::vector<std::string>& labels,
                       const ContactSheetOptions& options = {});

}  // namespace springy::render

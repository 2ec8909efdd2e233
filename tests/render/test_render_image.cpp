// PNG round trip and the contact sheet.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <unistd.h>

#include "render/error.h"
#include "render/image.h"
#include "test_util.h"

using namespace springy::render;
namespace fs = std::filesystem;

namespace {
fs::path tempDir() {
  const fs::path dir = fs::temp_directory_path() / ("springy_render_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

Image pattern(int w, int h, int seed) {
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.resize(static_cast<std::size_t>(w * h * 4));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>((y * w + x) * 4);
      img.rgba[i] = static_cast<std::uint8_t>((x * 7 + seed * 31) & 255);
      img.rgba[i + 1] = static_cast<std::uint8_t>((y * 13 + seed) & 255);
      img.rgba[i + 2] = static_cast<std::uint8_t>((x * y + seed * 5) & 255);
      img.rgba[i + 3] = static_cast<std::uint8_t>(y == 0 ? 255 : (x * 3) & 255);
    }
  return img;
}
}  // namespace

TEST(RenderImage, PngRoundTripIsExact) {
  const fs::path dir = tempDir();
  const Image img = pattern(37, 21, 3);  // odd sizes: no row padding assumptions
  const std::string path = (dir / "round.png").string();
  writePng(path, img);
  const Image back = readPng(path);
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 21);
  EXPECT_EQ(back.rgba, img.rgba);  // includes row order: row 0 stays row 0
  fs::remove_all(dir);
}

TEST(RenderImage, PngErrorsNameThePath) {
  const Image img = pattern(4, 4, 0);
  try {
    writePng("/nonexistent-dir/x.png", img);
    FAIL();
  } catch (const RenderError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.png"), std::string::npos);
  }
  EXPECT_THROW(readPng("/nonexistent-dir/x.png"), RenderError);
  EXPECT_THROW(writePng("/tmp/x.png", 5, 5, img.rgba), RenderError);  // size mismatch
}

TEST(RenderImage, ContactSheetGridAndLabels) {
  std::vector<Image> images;
  std::vector<std::string> labels;
  for (int i = 0; i < 5; ++i) {
    Image im;
    im.width = 120;
    im.height = 60;
    im.rgba.assign(120 * 60 * 4, 255);
    for (std::size_t p = 0; p < im.rgba.size(); p += 4) {  // solid colour per cell
      im.rgba[p] = static_cast<std::uint8_t>(50 * i);
      im.rgba[p + 1] = 0;
      im.rgba[p + 2] = 100;
    }
    images.push_back(im);
    labels.push_back("t = " + std::to_string(i) + ".50 s");
  }
  ContactSheetOptions o;
  o.columns = 3;
  o.padding = 4;
  const Image sheet = makeContactSheet(images, labels, o);
  ASSERT_EQ(sheet.width, 4 + 3 * (120 + 4));
  ASSERT_GT(sheet.height, 4 + 2 * (60 + 4));  // two rows plus label strips
  const int rowStride = (sheet.height - 4) / 2;
  // Image 4 is in row 1, column 1: its centre pixel has its colour.
  const glm::vec3 c = test::pixel(sheet.rgba, sheet.width, 4 + 124 + 60, 4 + rowStride + 30);
  EXPECT_EQ(c, glm::vec3(200.0f, 0.0f, 100.0f));
  // The label strip under image 0 contains bright text pixels; the empty 6th cell does not.
  int bright = 0, brightEmpty = 0;
  for (int y = 4 + 60; y < 4 + rowStride - 4; ++y)
    for (int x = 4; x < 124; ++x) bright += test::pixel(sheet.rgba, sheet.width, x, y).r > 150;
  for (int y = 4 + rowStride + 60; y < sheet.height; ++y)
    for (int x = 4 + 2 * 124; x < sheet.width; ++x)
      brightEmpty += test::pixel(sheet.rgba, sheet.width, x, y).r > 150;
  EXPECT_GT(bright, 10);
  EXPECT_EQ(brightEmpty, 0);
  EXPECT_THROW(makeContactSheet(images, {"only one"}, o), RenderError);
}

#include "render/image.h"

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>

#include "render/error.h"

namespace springy::render {

namespace {

void checkSize(const std::string& what, int width, int height, std::span<const std::uint8_t> rgba) {
  if (width <= 0 || height <= 0 ||
      rgba.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4)
    throw RenderError(what + ": size " + std::to_string(rgba.size()) + " bytes does not match " +
                      std::to_string(width) + "x" + std::to_string(height) + " RGBA");
}

void append(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(context);
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), bytes, bytes + size);
}

std::string errnoText(int error) { return std::strerror(error); }

// CRC-32 of a PNG chunk's type and data (ISO 3309, as PNG specifies it), bit by bit: one short
// chunk per image.
std::uint32_t pngCrc(const std::uint8_t* bytes, std::size_t count) {
  std::uint32_t crc = 0xffffffffu;
  for (std::size_t i = 0; i < count; ++i) {
    crc ^= bytes[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xffffffffu;
}

void appendBigEndian(std::string& out, std::uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((value >> shift) & 0xffu));
}

// Inserts the tEXt chunk "Software: made with springy" after the signature and IHDR (8 + 25
// bytes), where a reader of the first bytes finds it.
void markPng(std::vector<std::uint8_t>& png) {
  constexpr std::size_t kAfterHeader = 8 + 4 + 4 + 13 + 4;
  const std::string typeAndText = "tEXtSoftware" + std::string(1, '\0') + std::string(kSpringyMark);
  std::string chunk;
  appendBigEndian(chunk, static_cast<std::uint32_t>(typeAndText.size() - 4));
  chunk += typeAndText;
  appendBigEndian(chunk, pngCrc(reinterpret_cast<const std::uint8_t*>(typeAndText.data()), typeAndText.size()));
  png.insert(png.begin() + static_cast<std::ptrdiff_t>(kAfterHeader), chunk.begin(), chunk.end());
}

}  // namespace

std::vector<std::uint8_t> encodePng(int width, int height, std::span<const std::uint8_t> rgba) {
  checkSize("encodePng", width, height, rgba);
  // stb's flip flag is global state; rows are already top-down, so keep it off.
  stbi_flip_vertically_on_write(0);
  std::vector<std::uint8_t> png;
  if (!stbi_write_png_to_func(append, &png, width, height, 4, rgba.data(), width * 4) || png.empty())
    throw RenderError("encodePng: cannot encode a " + std::to_string(width) + "x" + std::to_string(height) +
                      " image");
  markPng(png);
  return png;
}

void writePng(const std::string& path, int width, int height, std::span<const std::uint8_t> rgba) {
  checkSize("writePng '" + path + "'", width, height, rgba);
  const std::vector<std::uint8_t> png = encodePng(width, height, rgba);
  // Plain POSIX calls with every result checked: stbi_write_png ignores fwrite's and fclose's
  // results, so a full disk gave a truncated file and success.
  auto fail = [&](const std::string& what, int error) {
    throw RenderError("writePng '" + path + "': " + what + ": " + errnoText(error));
  };
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) fail("cannot open", errno);
  std::size_t done = 0;
  while (done < png.size()) {
    const ssize_t n = ::write(fd, png.data() + done, png.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : EIO;
      ::close(fd);
      fail("cannot write", error);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) fail("cannot write", errno);
}

Image readPng(const std::string& path) {
  int w = 0, h = 0, channels = 0;
  std::unique_ptr<stbi_uc, void (*)(void*)> data(stbi_load(path.c_str(), &w, &h, &channels, 4),
                                                 stbi_image_free);
  if (!data)
    throw RenderError("readPng: cannot read '" + path + "': " + stbi_failure_reason());
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(data.get(), data.get() + static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
  return img;
}

Image makeContactSheet(const std::vector<Image>& images, const std::vector<std::string>& labels,
                       const ContactSheetOptions& o) {
  if (images.empty()) throw RenderError("makeContactSheet: no images");
  if (!labels.empty() && labels.size() != images.size())
    throw RenderError("makeContactSheet: " + std::to_string(labels.size()) + " labels for " +
                      std::to_string(images.size()) + " images");
  int cellW = 0, cellH = 0;
  for (const Image& im : images) {
    cellW = std::max(cellW, im.width);
    cellH = std::max(cellH, im.height);
  }
  std::unique_ptr<Font> font;
  int labelH = 0;
  if (!labels.empty()) {
    font = std::make_unique<Font>(o.fontPath, o.labelPixelHeight);
    labelH = font->lineHeight() + 4;
    for (const std::string& l : labels) cellW = std::max(cellW, font->textWidth(l) + 4);
  }
  const int n = static_cast<int>(images.size());
  const int cols = std::clamp(o.columns, 1, n);
  const int rows = (n + cols - 1) / cols;
  Image sheet;
  sheet.width = o.padding + cols * (cellW + o.padding);
  sheet.height = o.padding + rows * (cellH + labelH + o.padding);
  sheet.rgba.resize(static_cast<std::size_t>(sheet.width) * static_cast<std::size_t>(sheet.height) * 4);
  for (std::size_t i = 0; i < sheet.rgba.size(); i += 4) {
    sheet.rgba[i] = o.background[0];
    sheet.rgba[i + 1] = o.background[1];
    sheet.rgba[i + 2] = o.background[2];
    sheet.rgba[i + 3] = 255;
  }
  for (int i = 0; i < n; ++i) {
    const Image& im = images[static_cast<std::size_t>(i)];
    if (im.rgba.size() != static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height) * 4)
      throw RenderError("makeContactSheet: image " + std::to_string(i) + " has a bad pixel buffer");
    const int cx = o.padding + (i % cols) * (cellW + o.padding);
    const int cy = o.padding + (i / cols) * (cellH + labelH + o.padding);
    const int ox = cx + (cellW - im.width) / 2, oy = cy + (cellH - im.height) / 2;
    for (int y = 0; y < im.height; ++y)
      std::memcpy(sheet.rgba.data() + (static_cast<std::size_t>(oy + y) * static_cast<std::size_t>(sheet.width) +
                                       static_cast<std::size_t>(ox)) * 4,
                  im.rgba.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(im.width) * 4,
                  static_cast<std::size_t>(im.width) * 4);
    if (font) {
      const std::string& label = labels[static_cast<std::size_t>(i)];
      const int tx = cx + (cellW - font->textWidth(label)) / 2;
      font->draw(sheet, tx, cy + cellH + 2, label, glm::vec3(0.92f));
    }
  }
  return sheet;
}

}  // namespace springy::render

// Why: rendering happens without a display. GlContext owns an OSMesa core-profile (>= 3.3) context
// and the framebuffer objects a frame is drawn into (4x multisampled when anti-aliasing is on,
// resolved with glBlitFramebuffer), so callers never touch OSMesa or FBO plumbing.
// One GlContext per thread; it is made current on construction and by makeCurrent().
#pragma once
#include <cstdint>
#include <vector>

namespace springy::render {

class GlContext {
public:
  // Throws RenderError if the context or the framebuffers cannot be created.
  // width, height in 1..16384. antiAlias: 4x MSAA (llvmpipe's maximum).
  GlContext(int width, int height, bool antiAlias);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  void makeCurrent();
  int width() const { return width_; }
  int height() const { return height_; }
  bool antiAlias() const { return samples_ > 1; }
  int samples() const { return samples_; }

  // Binds the framebuffer the scene is drawn into (multisampled when anti-aliasing is on) and
  // sets the viewport to the full frame.
  void bindDrawTarget();
  // Resolves the multisampled buffer (no-op without MSAA) and reads RGBA8 pixels, rows TOP-DOWN,
  // into rgba (resized to width*height*4).
  void readPixels(std::vector<std::uint8_t>& rgba);

  // Renderer/driver strings, for logs.
  const char* glRenderer() const;
  const char* glVersion() const;

private:
  void destroyFramebuffers();
  int width_;
  int height_;
  int samples_ = 0;
  void* ctx_ = nullptr;                  // OSMesaContext
  std::vector<std::uint8_t> osmesaBuffer_;  // OSMesa's own (unused) window buffer
  std::vector<std::uint8_t> scratch_;       // bottom-up rows from glReadPixels
  unsigned msFbo_ = 0, msColor_ = 0, msDepth_ = 0;  // multisampled target (AA on)
  unsigned fbo_ = 0, color_ = 0, depth_ = 0;        // single-sample target / resolve target
};

}  // namespace springy::render

// Why: rendering happens without a display. GlContext owns an OSMesa core-profile (>= 3.3) context
// and the framebuffer objects a frame is drawn into, so callers never touch OSMesa or FBO
// plumbing. Three kinds of scene target:
//   Plain        the scene is drawn straight into the final framebuffer;
//   Msaa4        a 4x multisampled framebuffer, resolved into the final one (glBlitFramebuffer);
//   PostProcess  a single-sample framebuffer whose colour is a texture (sceneTexture()) that a
//                full-screen pass (the renderer's FXAA) reads while drawing the final framebuffer.
// One GlContext per thread; it is made current on construction and by makeCurrent().
#pragma once
#include <cstdint>
#include <vector>

namespace springy::render {

enum class SceneTarget { Plain, Msaa4, PostProcess };

class GlContext {
public:
  // Throws RenderError if the context or the framebuffers cannot be created.
  // width, height in 1..16384. Msaa4: 4 samples is llvmpipe's maximum.
  GlContext(int width, int height, SceneTarget target);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  void makeCurrent();
  int width() const { return width_; }
  int height() const { return height_; }
  SceneTarget target() const { return target_; }
  int samples() const { return samples_; }

  // Binds the framebuffer the scene is drawn into and sets the viewport to the full frame.
  void bindDrawTarget();
  // Msaa4: resolves into the final framebuffer. Other targets: no-op.
  void resolve();
  // Binds the final (single-sample, colour only needed) framebuffer and sets the viewport.
  void bindFinalTarget();
  // PostProcess: the scene colour texture (0 otherwise).
  unsigned sceneTexture() const { return sceneColorTex_; }

  // A cached background: what the scene target holds before the frame's meshes go in (the
  // renderer's sky and grounds, unchanged while the camera, the light and the grounds are), drawn
  // once and copied into each frame. Plain and PostProcess only (a single-sample image cannot be
  // copied into a multisampled one). The targets are created on first use.
  // Binds the target the background is drawn into (colour texture + depth) and sets the viewport.
  void bindBackgroundTarget();
  unsigned backgroundTexture() const { return bgColorTex_; }
  // PostProcess: binds the target for the background's anti-aliased image (colour + depth).
  void bindBackgroundFinalTarget();
  // Copies the background's colour and depth into the scene target, which is left bound: the
  // pixels x0 <= x < x1, y0 <= y < y1 (GL's bottom-up rows; empty: nothing is copied).
  void restoreBackground(int x0, int y0, int x1, int y1);
  // PostProcess: copies the background's anti-aliased colour into the final framebuffer, which
  // is left bound (the same rectangle).
  void restoreBackgroundFinal(int x0, int y0, int x1, int y1);
  // Reads the final framebuffer as RGBA8 into rgba (resized to width*height*4). topDown: row 0
  // is the top of the image (one extra copy); otherwise GL's bottom-up order, straight from
  // glReadPixels.
  void readPixels(std::vector<std::uint8_t>& rgba, bool topDown);

  // Renderer/driver strings, for logs.
  const char* glRenderer() const;
  const char* glVersion() const;

private:
  void destroyFramebuffers();
  int width_;
  int height_;
  SceneTarget target_;
  int samples_ = 0;
  void* ctx_ = nullptr;                  // OSMesaContext
  std::vector<std::uint8_t> osmesaBuffer_;  // OSMesa's own (unused) window buffer
  std::vector<std::uint8_t> scratch_;       // bottom-up rows from glReadPixels
  unsigned msFbo_ = 0, msColor_ = 0, msDepth_ = 0;  // multisampled target (AA on)
  unsigned fbo_ = 0, color_ = 0, depth_ = 0;        // final framebuffer (Plain: also the scene)
  unsigned sceneFbo_ = 0, sceneColorTex_ = 0, sceneDepth_ = 0;  // PostProcess scene target
  unsigned bgFbo_ = 0, bgColorTex_ = 0, bgDepth_ = 0;           // cached background (scene)
  unsigned bgFinalFbo_ = 0, bgFinalColor_ = 0, bgFinalDepth_ = 0;  // ... and anti-aliased
  unsigned drawFbo() const;
  void copy(unsigned from, unsigned to, unsigned mask, int x0, int y0, int x1, int y1);
};

}  // namespace springy::render

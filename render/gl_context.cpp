#include "render/gl_context.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <cstring>
#include <string>

#include "render/error.h"

namespace springy::render {

namespace {
std::string fboStatusText(GLenum s) {
  switch (s) {
    case GL_FRAMEBUFFER_COMPLETE: return "complete";
    case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT: return "incomplete attachment";
    case GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT: return "missing attachment";
    case GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE: return "incomplete multisample";
    case GL_FRAMEBUFFER_UNSUPPORTED: return "unsupported";
    default: return "status 0x" + std::to_string(s);
  }
}

void makeTarget(GLsizei w, GLsizei h, GLsizei samples, unsigned& fbo, unsigned& color,
                unsigned& depth) {
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glGenRenderbuffers(1, &color);
  glBindRenderbuffer(GL_RENDERBUFFER, color);
  if (samples > 1) glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w, h);
  else glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
  glGenRenderbuffers(1, &depth);
  glBindRenderbuffer(GL_RENDERBUFFER, depth);
  if (samples > 1)
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
  else glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw RenderError("GlContext: framebuffer (" + std::to_string(w) + "x" + std::to_string(h) +
                      ", " + std::to_string(samples) + " samples) is " + fboStatusText(status));
}
// A single-sample framebuffer whose colour attachment is a texture (linear filtering, clamped),
// for a post-processing pass to sample.
void makeTextureTarget(GLsizei w, GLsizei h, unsigned& fbo, unsigned& tex, unsigned& depth) {
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glBindTexture(GL_TEXTURE_2D, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
  glGenRenderbuffers(1, &depth);
  glBindRenderbuffer(GL_RENDERBUFFER, depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw RenderError("GlContext: scene texture framebuffer (" + std::to_string(w) + "x" +
                      std::to_string(h) + ") is " + fboStatusText(status));
}
}  // namespace

GlContext::GlContext(int width, int height, SceneTarget target)
    : width_(width), height_(height), target_(target) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw RenderError("GlContext: invalid frame size " + std::to_string(width) + "x" +
                      std::to_string(height));
  const int attribs[] = {OSMESA_FORMAT,
                         OSMESA_RGBA,
                         OSMESA_DEPTH_BITS,
                         24,
                         OSMESA_STENCIL_BITS,
                         0,
                         OSMESA_ACCUM_BITS,
                         0,
                         OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION,
                         3,
                         OSMESA_CONTEXT_MINOR_VERSION,
                         3,
                         0};
  OSMesaContext ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!ctx)
    throw RenderError(
        "GlContext: OSMesaCreateContextAttribs failed (OpenGL 3.3 core profile unavailable; "
        "check libosmesa6 and GALLIUM_DRIVER, which should be unset or llvmpipe)");
  ctx_ = ctx;
  // OSMesa needs a window buffer to make the context current; we draw into our own FBOs.
  osmesaBuffer_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4, 0);
  try {
    makeCurrent();
    const GLsizei w = width, h = height;
    if (target == SceneTarget::Msaa4) {
      samples_ = 4;
      makeTarget(w, h, samples_, msFbo_, msColor_, msDepth_);
    }
    if (target == SceneTarget::PostProcess) makeTextureTarget(w, h, sceneFbo_, sceneColorTex_, sceneDepth_);
    makeTarget(w, h, 0, fbo_, color_, depth_);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (glGetError() != GL_NO_ERROR) throw RenderError("GlContext: GL error while creating FBOs");
  } catch (...) {
    destroyFramebuffers();
    OSMesaDestroyContext(ctx);
    ctx_ = nullptr;
    throw;
  }
}

GlContext::~GlContext() {
  if (!ctx_) return;
  makeCurrent();
  destroyFramebuffers();
  OSMesaDestroyContext(static_cast<OSMesaContext>(ctx_));
}

void GlContext::destroyFramebuffers() {
  const unsigned fbos[] = {msFbo_, fbo_, sceneFbo_, bgFbo_, bgFinalFbo_};
  const unsigned rbs[] = {msColor_, msDepth_, color_, depth_, sceneDepth_, bgDepth_, bgFinalColor_, bgFinalDepth_};
  for (unsigned f : fbos)
    if (f) glDeleteFramebuffers(1, &f);
  for (unsigned r : rbs)
    if (r) glDeleteRenderbuffers(1, &r);
  for (unsigned t : {sceneColorTex_, bgColorTex_})
    if (t) glDeleteTextures(1, &t);
  msFbo_ = msColor_ = msDepth_ = fbo_ = color_ = depth_ = 0;
  sceneFbo_ = sceneColorTex_ = sceneDepth_ = 0;
  bgFbo_ = bgColorTex_ = bgDepth_ = bgFinalFbo_ = bgFinalColor_ = bgFinalDepth_ = 0;
}

void GlContext::makeCurrent() {
  if (!OSMesaMakeCurrent(static_cast<OSMesaContext>(ctx_), osmesaBuffer_.data(), GL_UNSIGNED_BYTE,
                         width_, height_))
    throw RenderError("GlContext: OSMesaMakeCurrent failed");
}

unsigned GlContext::drawFbo() const {
  return target_ == SceneTarget::Msaa4 ? msFbo_ : target_ == SceneTarget::PostProcess ? sceneFbo_ : fbo_;
}

void GlContext::bindDrawTarget() {
  glBindFramebuffer(GL_FRAMEBUFFER, drawFbo());
  glViewport(0, 0, width_, height_);
}

void GlContext::bindBackgroundTarget() {
  if (target_ == SceneTarget::Msaa4) throw RenderError("GlContext: no cached background with a multisampled target");
  if (!bgFbo_) makeTextureTarget(width_, height_, bgFbo_, bgColorTex_, bgDepth_);
  glBindFramebuffer(GL_FRAMEBUFFER, bgFbo_);
  glViewport(0, 0, width_, height_);
}

void GlContext::bindBackgroundFinalTarget() {
  if (target_ != SceneTarget::PostProcess) throw RenderError("GlContext: an anti-aliased background needs PostProcess");
  if (!bgFinalFbo_) makeTarget(width_, height_, 0, bgFinalFbo_, bgFinalColor_, bgFinalDepth_);
  glBindFramebuffer(GL_FRAMEBUFFER, bgFinalFbo_);
  glViewport(0, 0, width_, height_);
}

// Same formats, no scaling and no scissor: llvmpipe copies the memory.
void GlContext::copy(unsigned from, unsigned to, unsigned mask, int x0, int y0, int x1, int y1) {
  if (!from) throw RenderError("GlContext: the cached background was never drawn");
  if (x1 > x0 && y1 > y0) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, from);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, to);
    glBlitFramebuffer(x0, y0, x1, y1, x0, y0, x1, y1, mask, GL_NEAREST);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, to);
  glViewport(0, 0, width_, height_);
}

void GlContext::restoreBackground(int x0, int y0, int x1, int y1) {
  copy(bgFbo_, drawFbo(), GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT, x0, y0, x1, y1);
}

void GlContext::restoreBackgroundFinal(int x0, int y0, int x1, int y1) {
  copy(bgFinalFbo_, fbo_, GL_COLOR_BUFFER_BIT, x0, y0, x1, y1);
}

void GlContext::resolve() {
  if (target_ != SceneTarget::Msaa4) return;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, msFbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo_);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

void GlContext::bindFinalTarget() {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
}

void GlContext::readPixels(std::vector<std::uint8_t>& rgba, bool topDown) {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  const std::size_t row = static_cast<std::size_t>(width_) * 4;
  const std::size_t size = row * static_cast<std::size_t>(height_);
  rgba.resize(size);
  if (!topDown) {
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  } else {
    scratch_.resize(size);
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, scratch_.data());
    // GL rows are bottom-up; hand out top-down rows.
    for (int y = 0; y < height_; ++y)
      std::memcpy(rgba.data() + static_cast<std::size_t>(y) * row,
                  scratch_.data() + static_cast<std::size_t>(height_ - 1 - y) * row, row);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  const GLenum err = glGetError();
  if (err != GL_NO_ERROR)
    throw RenderError("GlContext::readPixels: GL error 0x" + std::to_string(err));
}

const char* GlContext::glRenderer() const {
  return reinterpret_cast<const char*>(glGetString(GL_RENDERER));
}
const char* GlContext::glVersion() const {
  return reinterpret_cast<const char*>(glGetString(GL_VERSION));
}

}  // namespace springy::render

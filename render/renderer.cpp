#include "render/renderer.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <glm/gtc/type_ptr.hpp>
#include <limits>
#include <optional>
#include <string>

#include "render/error.h"
#include "render/gl_context.h"
#include "render/gl_program.h"
#include "render/look.h"
#include "render/refine.h"
#include "render/shaders.h"
#include "render/shadow_fit.h"

namespace springy::render {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei indexCount = 0;
  std::size_t vertexCount = 0;
  std::vector<std::uint32_t> indices;  // kept for normal recomputation
  std::vector<float> interleaved;      // position + normal per vertex
  Material material;
  Bounds bounds;
  // Drawn from a finer surface than given (PN triangles, refine.h): coarse `indices` give the
  // normals the patches need; the buffers hold the refined mesh.
  PnRefinement refinement;
  std::vector<glm::vec3> coarsePos, coarseNormals, refinedPos;
  int occluder = -1;  // this frame's index in the contact-shadow occluder list
  bool dynamic = false;
  bool hasPositions = false;
  // Ground only:
  bool ground = false;
  glm::vec3 groundOrigin{0.0f}, groundU{1, 0, 0}, groundV{0, 0, 1}, groundB{0.5f};
  glm::vec3 groundRestU{1, 0, 0}, groundRestV{0, 0, 1};  // the axes as added (placeGround turns them)
  float tile = 1.0f, extent = 1.0f;
};

void checkTriangles(std::span<const std::uint32_t> tris, std::size_t vertexCount) {
  if (tris.size() % 3 != 0)
    throw RenderError("Renderer: triangle index count " + std::to_string(tris.size()) +
                      " is not a multiple of 3");
  for (std::uint32_t i : tris)
    if (i >= vertexCount)
      throw RenderError("Renderer: triangle index " + std::to_string(i) + " out of range (" +
                        std::to_string(vertexCount) + " vertices)");
}

glm::vec3 toLinear(glm::vec3 c) { return srgbToLinear(c); }

constexpr int kMaxOccluders = 16;  // MAX_OCCLUDERS in the mesh shader

// The pixels lo <= p < hi (GL's bottom-up rows); empty when hi <= lo on an axis.
struct PixelRect {
  glm::ivec2 lo{std::numeric_limits<int>::max()}, hi{std::numeric_limits<int>::min()};
  bool empty() const { return hi.x <= lo.x || hi.y <= lo.y; }
  // The smallest rectangle holding this one and r.
  void add(const PixelRect& r) {
    if (r.empty()) return;
    lo = glm::min(lo, r.lo);
    hi = glm::max(hi, r.hi);
  }
  static PixelRect fromScissor(const glm::ivec4& r) { return {{r[0], r[1]}, {r[0] + r[2], r[1] + r[3]}}; }
};

// Area-weighted smooth vertex normals of a triangle mesh (unit; (0, 1, 0) where undefined).
void smoothNormals(std::span<const glm::vec3> p, std::span<const std::uint32_t> tris, std::vector<glm::vec3>& normals) {
  normals.assign(p.size(), glm::vec3(0.0f));
  for (std::size_t t = 0; t + 2 < tris.size(); t += 3) {
    const std::uint32_t a = tris[t], b = tris[t + 1], c = tris[t + 2];
    const glm::vec3 n = glm::cross(p[b] - p[a], p[c] - p[a]);  // |n| = 2 * area
    normals[a] += n;
    normals[b] += n;
    normals[c] += n;
  }
  for (glm::vec3& n : normals) {
    const float len = glm::length(n);
    n = len > 0.0f && std::isfinite(len) ? n / len : glm::vec3(0, 1, 0);
  }
}

}  // namespace

// ---------------------------------------------------------------- Impl
struct Renderer::Impl {
  RenderSettings settings;
  GlContext ctx;
  // Mesh shader variants, compiled on first use: index = shadows | ground << 1 | flat << 2 |
  // jelly << 3 | contact << 4.
  std::optional<Program> meshProgs[32];
  Program depthProg, skyProg, overlayProg, fxaaEdgeProg, fxaaProg;
  // Per frame: which mesh variants got this frame's shared uniforms, and what they are.
  unsigned framePrepared = 0;
  struct FrameUniforms {
    glm::mat4 viewProj{1.0f}, lightVP{1.0f};
    float normalOffset = 0.0f;
    glm::vec3 ambientSky{0.0f}, ambientGround{0.0f};
    int occluders = 0;
    glm::vec3 occCentre[kMaxOccluders], occRadii[kMaxOccluders];
  } frameUniforms;
  Program* current = nullptr;
  GLuint emptyVao = 0;
  GLuint shadowFbo = 0, shadowTex = 0;
  int shadowSize = 0;  // current shadow map size (fitted, at most settings.shadowMapSize)
  GLuint overlayTex = 0;
  int overlayW = 0, overlayH = 0;
  std::vector<std::string> overlayLines;
  bool overlayDirty = false;
  std::unique_ptr<Font> font;
  std::vector<GpuMesh> meshes;
  Camera camera;
  Light light;
  glm::vec3 skyTop{0.36f, 0.56f, 0.84f}, skyBottom{0.86f, 0.90f, 0.95f};
  RenderTimings timings;
  // Per frame: the drawable meshes of each pass, in mesh order (kept to reuse their memory).
  std::vector<const GpuMesh*> opaque, grounds, translucent;
  // The cached background (RenderSettings::cacheBackground): whether this frame starts from it,
  // and what it was drawn with (backgroundKey); empty: never drawn.
  bool fromBackground = false;
  std::vector<float> backgroundDrawnWith;
  // Per frame, with the background: the screen rectangle of what the frame draws over it, or
  // all of it. And where the scene and final targets may differ from the background (what the
  // last frame drew there), the only pixels the next frame copies back.
  PixelRect changed;
  bool changedAll = false;
  PixelRect sceneDirty, finalDirty;
  static SceneTarget targetFor(const RenderSettings& s) {
    if (!s.antiAlias) return SceneTarget::Plain;
    return s.antiAliasMethod == AntiAliasMethod::Msaa4 ? SceneTarget::Msaa4 : SceneTarget::PostProcess;
  }

  explicit Impl(const RenderSettings& s) : settings(s), ctx(s.width, s.height, targetFor(s)) {
    if (ctx.target() == SceneTarget::PostProcess) {
      fxaaEdgeProg = Program(kSkyVs, fxaaSource(true).c_str(), "FXAA edges");
      fxaaProg = Program(kMidVs, fxaaSource(false).c_str(), "FXAA");
    }
    depthProg = Program(kDepthVs, kDepthFs, "shadow depth");
    skyProg = Program(kSkyVs, kSkyFs, "sky");
    overlayProg = Program(kOverlayVs, kOverlayFs, "overlay");
    glGenVertexArrays(1, &emptyVao);
    if (settings.shadows) {
      if (settings.shadowMapSize < 16 || settings.shadowMapSize > 8192)
        throw RenderError("Renderer: shadowMapSize " + std::to_string(settings.shadowMapSize) +
                          " outside 16..8192");
      glGenTextures(1, &shadowTex);
      glBindTexture(GL_TEXTURE_2D, shadowTex);
      shadowSize = settings.shadowMapSize;
      glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, shadowSize, shadowSize, 0,
                   GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
      glGenFramebuffers(1, &shadowFbo);
      glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadowTex, 0);
      glDrawBuffer(GL_NONE);
      glReadBuffer(GL_NONE);
      if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw RenderError("Renderer: shadow framebuffer incomplete");
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }
    glDisable(GL_DITHER);
    const GLenum err = glGetError();
    if (err != GL_NO_ERROR)
      throw RenderError("Renderer: GL error 0x" + std::to_string(err) + " during setup");
  }

  ~Impl() {
    ctx.makeCurrent();
    for (GpuMesh& m : meshes) freeMesh(m);
    if (emptyVao) glDeleteVertexArrays(1, &emptyVao);
    if (shadowTex) glDeleteTextures(1, &shadowTex);
    if (shadowFbo) glDeleteFramebuffers(1, &shadowFbo);
    if (overlayTex) glDeleteTextures(1, &overlayTex);
  }

  static void freeMesh(GpuMesh& m) {
    if (m.vao) glDeleteVertexArrays(1, &m.vao);
    if (m.vbo) glDeleteBuffers(1, &m.vbo);
    if (m.ebo) glDeleteBuffers(1, &m.ebo);
    m.vao = m.vbo = m.ebo = 0;
  }

  GpuMesh& mesh(MeshId id) {
    if (id >= meshes.size()) throw RenderError("Renderer: unknown mesh id " + std::to_string(id));
    return meshes[id];
  }

  MeshId createMesh(std::size_t vertexCount, std::span<const std::uint32_t> tris,
                    const Material& mat, bool dynamic, bool refine = true) {
    checkTriangles(tris, vertexCount);
    GpuMesh m;
    m.vertexCount = vertexCount;
    m.indices.assign(tris.begin(), tris.end());
    m.material = mat;
    m.dynamic = dynamic;
    if (dynamic && refine && !mat.flat && settings.smoothSilhouettes)
      m.refinement = PnRefinement(tris, vertexCount, PnRefinement::levelFor(tris.size() / 3));
    const std::vector<std::uint32_t>& drawn = m.refinement.active() ? m.refinement.triangles() : m.indices;
    const std::size_t drawnVertices = m.refinement.active() ? m.refinement.vertexCount() : vertexCount;
    m.indexCount = static_cast<GLsizei>(drawn.size());
    m.interleaved.assign(drawnVertices * 6, 0.0f);
    glGenVertexArrays(1, &m.vao);
    glGenBuffers(1, &m.vbo);
    glGenBuffers(1, &m.ebo);
    glBindVertexArray(m.vao);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(m.interleaved.size() * sizeof(float)),
                 nullptr, dynamic ? GL_STREAM_DRAW : GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(drawn.size() * sizeof(std::uint32_t)), drawn.data(),
                 GL_STATIC_DRAW);
    const auto stride = static_cast<GLsizei>(6 * sizeof(float));
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glBindVertexArray(0);
    meshes.push_back(std::move(m));
    return static_cast<MeshId>(meshes.size() - 1);
  }

  // Area-weighted smooth normals, interleaved with positions, uploaded to the VBO. A refined
  // mesh: the coarse normals shape the PN patches, the refined surface gets its own normals.
  void setPositions(GpuMesh& m, std::span<const float> pos, std::span<const std::uint8_t> flat = {}) {
    if (pos.size() != m.vertexCount * 3)
      throw RenderError("Renderer: got " + std::to_string(pos.size()) + " position floats for " +
                        std::to_string(m.vertexCount) + " vertices");
    m.coarsePos.resize(m.vertexCount);
    for (std::size_t i = 0; i < m.vertexCount; ++i) m.coarsePos[i] = {pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]};
    smoothNormals(m.coarsePos, m.indices, m.coarseNormals);
    const std::vector<glm::vec3>* drawnPos = &m.coarsePos;
    const std::vector<glm::vec3>* drawnNormals = &m.coarseNormals;
    if (m.refinement.active()) {
      m.refinement.evaluate(m.coarsePos, m.coarseNormals, m.refinedPos, flat);
      smoothNormals(m.refinedPos, m.refinement.triangles(), m.coarseNormals);  // reused as scratch
      drawnPos = &m.refinedPos;
    }
    Bounds b;
    for (std::size_t i = 0; i < drawnPos->size(); ++i) {
      const glm::vec3 p = (*drawnPos)[i], n = (*drawnNormals)[i];
      b.add(p);
      float* out = m.interleaved.data() + 6 * i;
      out[0] = p.x, out[1] = p.y, out[2] = p.z, out[3] = n.x, out[4] = n.y, out[5] = n.z;
    }
    m.bounds = b;
    m.hasPositions = true;
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    const auto bytes = static_cast<GLsizeiptr>(m.interleaved.size() * sizeof(float));
    if (m.dynamic) glBufferData(GL_ARRAY_BUFFER, bytes, nullptr, GL_STREAM_DRAW);  // orphan
    glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, m.interleaved.data());
    glBindBuffer(GL_ARRAY_BUFFER, 0);
  }

  Bounds casterBounds() const {
    Bounds b;
    for (const GpuMesh& m : meshes)
      if (!m.ground && m.hasPositions) b.add(m.bounds);
    return b;
  }

  bool drawable(const GpuMesh& m) const { return m.hasPositions && m.indexCount > 0; }

  void resizeShadowMap(int n) {
    if (n == shadowSize) return;
    glBindTexture(GL_TEXTURE_2D, shadowTex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, n, n, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
    glBindTexture(GL_TEXTURE_2D, 0);
    shadowSize = n;
  }

  // Rasterises the overlay lines into a premultiplied-alpha texture. Throws (and stays dirty,
  // so the next frame throws again) if the font cannot be loaded.
  void rebuildOverlay() {
    if (overlayLines.empty()) {
      overlayW = overlayH = 0;
      overlayDirty = false;
      return;
    }
    if (!font) {
      const float px = settings.overlayPixelHeight > 0.0f
                           ? settings.overlayPixelHeight
                           : std::max(12.0f, static_cast<float>(settings.height) / 36.0f);
      font = std::make_unique<Font>(settings.fontPath, px);
    }
    const int pad = std::max(4, static_cast<int>(font->pixelHeight() * 0.4f));
    int w = 0;
    for (const std::string& s : overlayLines) w = std::max(w, font->textWidth(s));
    Image img;
    img.width = std::min(w + 2 * pad + 1, settings.width);
    img.height = std::min(static_cast<int>(overlayLines.size()) * font->lineHeight() + 2 * pad + 1,
                          settings.height);
    img.rgba.assign(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 4, 0);
    fillRect(img, 0, 0, img.width, img.height, glm::vec3(0.0f), 0.45f);
    for (std::size_t i = 0; i < overlayLines.size(); ++i) {
      const int y = pad + static_cast<int>(i) * font->lineHeight();
      font->draw(img, pad + 1, y + 1, overlayLines[i], glm::vec3(0.0f), 0.85f);  // drop shadow
      font->draw(img, pad, y, overlayLines[i], glm::vec3(1.0f));
    }
    if (!overlayTex) glGenTextures(1, &overlayTex);
    glBindTexture(GL_TEXTURE_2D, overlayTex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, img.width, img.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 img.rgba.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    overlayW = img.width;
    overlayH = img.height;
    overlayDirty = false;
  }

  void use(Program& p) {
    if (current != &p) p.use(), current = &p;
  }

  Program& meshProgram(bool shadowsOn, const GpuMesh& m, bool contactOn) {
    const unsigned key = (shadowsOn ? 1u : 0u) | (m.ground ? 2u : 0u) | (m.material.flat && !m.ground ? 4u : 0u) |
                         (jelly(m) ? 8u : 0u) | (contactOn ? 16u : 0u);
    std::optional<Program>& p = meshProgs[key];
    if (!p) {
      const std::string fs = meshVariantSource(key & 1u, key & 2u, key & 4u, key & 8u, key & 16u);
      p.emplace(kMeshVs, fs.c_str(), "mesh");
    }
    use(*p);
    if (!(framePrepared & (1u << key))) {  // this frame's shared uniforms, once per variant
      framePrepared |= 1u << key;
      p->set("uViewProj", frameUniforms.viewProj);
      p->set("uLightViewProj", frameUniforms.lightVP);
      p->set("uNormalOffset", frameUniforms.normalOffset);
      p->set("uToLight", -glm::normalize(light.direction));
      p->set("uLightColour", light.colour);
      p->set("uAmbientSky", frameUniforms.ambientSky);
      p->set("uAmbientGround", frameUniforms.ambientGround);
      p->set("uOccluderCount", frameUniforms.occluders);
      if (frameUniforms.occluders > 0) {
        glUniform3fv(p->loc("uOccCentre"), frameUniforms.occluders, &frameUniforms.occCentre[0].x);
        glUniform3fv(p->loc("uOccRadii"), frameUniforms.occluders, &frameUniforms.occRadii[0].x);
      }
      p->set("uEye", camera.position);
      p->set("uShadowStep",
             settings.shadowSoftness / static_cast<float>(std::max(shadowSize, 1)));
      p->set("uShadowMap", 0);
      p->set("uSkyTop", skyTop);
      p->set("uSkyBottom", skyBottom);
      p->set("uHeight", static_cast<float>(settings.height));
    }
    return *p;
  }

  // Translucent bodies are shaded as gelatine (the JELLY variant).
  static bool jelly(const GpuMesh& m) { return !m.ground && m.material.alpha < 1.0f; }

  // Whether another body than m itself darkens it (the CONTACT variant is needed).
  bool contactOn(const GpuMesh& m) const { return frameUniforms.occluders > (m.occluder >= 0 ? 1 : 0); }

  void drawMesh(bool shadowsOn, const GpuMesh& m) { drawMesh(shadowsOn, m, contactOn(m)); }
  void drawMesh(bool shadowsOn, const GpuMesh& m, bool contact) {
    Program& p = meshProgram(shadowsOn, m, contact);
    p.set("uAlbedo", toLinear(m.material.colour));
    p.set("uAlpha", std::clamp(m.material.alpha, 0.0f, 1.0f));
    p.set("uSelf", m.occluder);
    if (m.ground) {
      p.set("uGroundOrigin", m.groundOrigin);
      p.set("uGroundU", m.groundU);
      p.set("uGroundV", m.groundV);
      p.set("uGroundB", toLinear(m.groundB));
      p.set("uTile", m.tile);
      p.set("uGroundExtent", m.extent);
    } else {
      p.set("uShininess", std::max(m.material.shininess, 1.0f));
      p.set("uSpecular", m.material.specular);
    }
    glBindVertexArray(m.vao);
    glDrawElements(GL_TRIANGLES, m.indexCount, GL_UNSIGNED_INT, nullptr);
  }

  // profilePasses: glFinish, then charge the time since the previous mark to `pass`.
  Clock::time_point passStart;
  void mark(RenderPass pass) {
    if (!settings.profilePasses) return;
    glFinish();
    const auto now = Clock::now();
    timings.passMs[static_cast<std::size_t>(pass)] +=
        std::chrono::duration<double, std::milli>(now - passStart).count();
    passStart = now;
  }

  // ---------------------------------------------------------------- the frame
  // One frame is this list of passes, in order. Each pass leaves the GL state the next expects;
  // with profilePasses each one's time (glFinish included) goes to its RenderPass entry.
  void render() {
    const Clock::time_point t0 = beginFrame();
    const bool shadowsOn = shadowPass();
    beginScene();
    opaquePass(shadowsOn);
    groundPass(shadowsOn);
    skyPass();
    translucentPass(shadowsOn);
    antiAliasPass();
    overlayPass();
    endFrame(t0);
  }

  // The context made current, this frame's camera, the overlay texture up to date.
  Clock::time_point beginFrame() {
    const auto t0 = Clock::now();
    passStart = t0;
    ctx.makeCurrent();
    current = nullptr;
    framePrepared = 0;
    if (overlayDirty) rebuildOverlay();
    const float aspect = static_cast<float>(settings.width) / static_cast<float>(settings.height);
    frameUniforms.viewProj = camera.viewProjection(aspect);
    prepareLook();
    return t0;
  }

  // Hemisphere ambient and contact-shadow occluders for this frame.
  // Ambient: the scene's grey ambient a, from above tinted by the sky's top colour, from below at
  // half strength tinted by the (first) ground's colour, each tint of luminance 1 and mixed
  // 35% into white (brightness as before: 1.0 a from above, 0.5 a from below).
  // Occluders: each dynamic body (the first kMaxOccluders) as the ellipsoid inscribed in its
  // bounding box.
  void prepareLook() {
    const auto tint = [](glm::vec3 linear) {
      const float lum = glm::dot(linear, glm::vec3(0.2126f, 0.7152f, 0.0722f));
      return lum > 1e-4f ? glm::mix(glm::vec3(1.0f), linear / lum, 0.35f) : glm::vec3(1.0f);
    };
    glm::vec3 groundColour = toLinear(skyBottom);
    for (const GpuMesh& m : meshes)
      if (m.ground) {
        groundColour = 0.5f * (toLinear(m.material.colour) + toLinear(m.groundB));
        break;
      }
    frameUniforms.ambientSky = light.ambient * tint(toLinear(skyTop));
    frameUniforms.ambientGround = 0.5f * light.ambient * tint(groundColour);
    frameUniforms.occluders = 0;
    for (GpuMesh& m : meshes) {
      m.occluder = -1;
      if (!settings.contactShadows || !m.dynamic || !drawable(m) || frameUniforms.occluders == kMaxOccluders) continue;
      const glm::vec3 half = 0.5f * (m.bounds.hi - m.bounds.lo);
      const float biggest = std::max({half.x, half.y, half.z});
      if (!(biggest > 0.0f) || !std::isfinite(biggest)) continue;
      m.occluder = frameUniforms.occluders++;
      frameUniforms.occCentre[m.occluder] = 0.5f * (m.bounds.hi + m.bounds.lo);
      frameUniforms.occRadii[m.occluder] = glm::max(half, glm::vec3(0.05f * biggest));
    }
  }

  // Depth from the light of every drawable mesh but the grounds, into the shadow map fitted to
  // them (shadow_fit.h). Returns whether the frame has shadows (off, or nothing casts).
  bool shadowPass() {
    frameUniforms.lightVP = glm::mat4(1.0f);
    frameUniforms.normalOffset = 0.0f;
    if (!settings.shadows) return false;
    const Bounds b = casterBounds();
    if (b.empty()) return false;
    const ShadowFit fit = fitShadowMap(b, light.direction, camera, settings);
    resizeShadowMap(fit.mapSize);
    frameUniforms.lightVP = fit.lightViewProj;
    frameUniforms.normalOffset = 1.5f * fit.texelWorld;
    glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo);
    glViewport(0, 0, shadowSize, shadowSize);
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.5f, 2.0f);
    use(depthProg);
    depthProg.set("uLightViewProj", frameUniforms.lightVP);
    for (const GpuMesh& m : meshes) {
      if (!drawable(m) || m.ground) continue;
      glBindVertexArray(m.vao);
      glDrawElements(GL_TRIANGLES, m.indexCount, GL_UNSIGNED_INT, nullptr);
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    mark(RenderPass::Shadow);
    return true;
  }

  // The scene target bound with a cleared depth buffer (LEQUAL), the shadow map on texture unit
  // 0, and the drawable meshes sorted into this frame's opaque, ground and translucent lists.
  // With the cached background, the target starts as a copy of it (redrawn first if out of
  // date); without, with a cleared depth buffer.
  void beginScene() {
    opaque.clear();
    grounds.clear();
    translucent.clear();
    for (const GpuMesh& m : meshes) {
      if (!drawable(m)) continue;
      if (m.ground) grounds.push_back(&m);
      else if (m.material.alpha < 1.0f) translucent.push_back(&m);
      else opaque.push_back(&m);
    }
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_TRUE);
    fromBackground = settings.cacheBackground && ctx.target() != SceneTarget::Msaa4;
    changed = PixelRect{};
    changedAll = false;
    if (fromBackground) {
      std::vector<float> key = backgroundKey();
      if (backgroundDrawnWith.empty() || key.size() != backgroundDrawnWith.size() ||
          std::memcmp(key.data(), backgroundDrawnWith.data(), key.size() * sizeof(float)) != 0) {
        drawBackground();
        backgroundDrawnWith = std::move(key);
      }
      ctx.restoreBackground(sceneDirty.lo.x, sceneDirty.lo.y, sceneDirty.hi.x, sceneDirty.hi.y);
    } else {
      ctx.bindDrawTarget();
      glClear(GL_DEPTH_BUFFER_BIT);
    }
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, shadowTex);
    mark(RenderPass::Background);
  }

  // Everything the background's pixels depend on: the camera, the light and ambient, the sky, and
  // each ground's place and colours (its shadows are drawn per frame). Compared bit for bit.
  std::vector<float> backgroundKey() const {
    std::vector<float> k;
    const auto put = [&k](const auto& v) {
      const float* f = glm::value_ptr(v);
      k.insert(k.end(), f, f + sizeof(v) / sizeof(float));
    };
    put(frameUniforms.viewProj);
    put(light.direction), put(light.colour), put(frameUniforms.ambientSky), put(frameUniforms.ambientGround);
    put(skyTop), put(skyBottom);
    for (const GpuMesh* g : grounds) {
      k.push_back(static_cast<float>(g - meshes.data()));
      put(g->material.colour), put(g->groundB), put(g->groundOrigin), put(g->groundU), put(g->groundV);
      k.insert(k.end(), {g->tile, g->extent, g->material.alpha});
    }
    return k;
  }

  // The grounds without what they receive, and the sky, into the background target; with FXAA
  // also its anti-aliased image.
  void drawBackground() {
    sceneDirty = finalDirty = whole();
    ctx.bindBackgroundTarget();
    glClear(GL_DEPTH_BUFFER_BIT);
    for (const GpuMesh* g : grounds) drawGround(*g, false, false);
    drawSky();
    if (ctx.target() != SceneTarget::PostProcess) return;
    ctx.bindBackgroundFinalTarget();
    fxaa(ctx.backgroundTexture());
    glEnable(GL_DEPTH_TEST);
  }

  void opaquePass(bool shadowsOn) {
    for (const GpuMesh* m : opaque) {
      drawMesh(shadowsOn, *m);
      drawnOver(*m);
    }
    mark(RenderPass::Opaque);
  }

  // Grounds (opaque: they mix the sky colour into their faded edge themselves). A ground
  // receives the shadow map only where the map reaches it: llvmpipe runs the shadow taps for
  // every pixel the shadowing variant shades, also where they return "lit". So each ground is
  // drawn without them, then again with them inside the screen rectangle around that
  // footprint (the same vertices and depths: LEQUAL passes exactly where it was drawn); the
  // image is the same.
  // With the cached background, the grounds are there already without what they receive: each is
  // drawn again only where it receives shadows.
  void groundPass(bool shadowsOn) {
    for (const GpuMesh* g : grounds) {
      // Contact shadows where some body's reach meets this ground on screen (none: unbounded).
      std::optional<glm::ivec4> contactRect;
      bool contact = false;
      if (frameUniforms.occluders > 0) {
        contactRect = contactFootprint(*g);
        contact = !contactRect || ((*contactRect)[2] > 0 && (*contactRect)[3] > 0);
      }
      const std::optional<glm::ivec4> rect =
          shadowsOn ? shadowFootprint(g->groundOrigin, g->groundU, g->groundV, light.direction, frameUniforms.lightVP,
                                      frameUniforms.viewProj, settings.width, settings.height)
                    : std::nullopt;
      if (!shadowsOn && !contact) {
        if (!fromBackground) drawGround(*g, false, false);
        continue;
      }
      if ((shadowsOn && !rect) || (contact && !contactRect)) {
        drawGround(*g, shadowsOn, contact);  // everywhere, with all it needs
        changedAll = true;
        continue;
      }
      if (!fromBackground) drawGround(*g, false, false);
      // Shadow taps inside the shadow map's footprint (outside it they return "lit"), contact
      // shadows inside the bodies' reach (outside it the occlusion is 0): both where the two
      // rectangles meet, the contact shadows alone in the rest of theirs.
      const PixelRect shadowed = shadowsOn && rect ? PixelRect::fromScissor(*rect) : PixelRect{};
      const PixelRect reached = contact && contactRect ? PixelRect::fromScissor(*contactRect) : PixelRect{};
      glEnable(GL_SCISSOR_TEST);
      const auto drawIn = [&](const PixelRect& r, bool withShadows) {
        if (r.empty()) return;
        glScissor(r.lo.x, r.lo.y, r.hi.x - r.lo.x, r.hi.y - r.lo.y);
        drawGround(*g, withShadows, contact);
        changed.add(r);
      };
      drawIn(shadowed, true);
      if (shadowed.empty()) {
        drawIn(reached, false);
      } else {  // the reach outside the footprint: below, above, left and right of it
        const glm::ivec2 c0 = reached.lo, c1 = reached.hi, s0 = shadowed.lo, s1 = shadowed.hi;
        const int y0 = std::max(c0.y, s0.y), y1 = std::min(c1.y, s1.y);
        drawIn({c0, {c1.x, std::min(c1.y, s0.y)}}, false);
        drawIn({{c0.x, std::max(c0.y, s1.y)}, c1}, false);
        drawIn({{c0.x, y0}, {std::min(c1.x, s0.x), y1}}, false);
        drawIn({{std::max(c0.x, s1.x), y0}, {c1.x, y1}}, false);
      }
      glDisable(GL_SCISSOR_TEST);
    }
    mark(RenderPass::Ground);
  }

  // A ground is pushed back in depth by a little (polygon offset): a cloth lying on the ground
  // (its vertices on the plane, y = 0) would otherwise fight it for every pixel.
  void drawGround(const GpuMesh& g, bool shadowsOn, bool contact) {
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 4.0f);
    drawMesh(shadowsOn, g, contact);
    glDisable(GL_POLYGON_OFFSET_FILL);
  }

  PixelRect whole() const { return {{0, 0}, {settings.width, settings.height}}; }

  // Adds a mesh's screen rectangle (its bounds' corners, widened by 2 pixels for rasterisation) to
  // what this frame draws over the background.
  void drawnOver(const GpuMesh& m) {
    if (!fromBackground || changedAll) return;
    glm::vec3 corners[8];
    for (int k = 0; k < 8; ++k)
      corners[k] = glm::vec3((k & 1) ? m.bounds.hi.x : m.bounds.lo.x, (k & 2) ? m.bounds.hi.y : m.bounds.lo.y,
                             (k & 4) ? m.bounds.hi.z : m.bounds.lo.z);
    const std::optional<glm::ivec4> r =
        screenRect(corners, frameUniforms.viewProj, settings.width, settings.height, 2.0f);
    if (r)
      changed.add(PixelRect::fromScissor(*r));
    else
      changedAll = true;  // unbounded: a corner behind the camera
  }

  // The screen rectangle where contact shadows can fall on ground g: every occluder's box of 2.5
  // of its radii (beyond it the shader's occlusion is exactly 0) that reaches the ground, dropped
  // onto it. Empty (width 0) when none reaches it; none when unbounded (behind the camera).
  std::optional<glm::ivec4> contactFootprint(const GpuMesh& g) const {
    const glm::vec3 n = glm::normalize(glm::cross(g.groundU, g.groundV));
    std::vector<glm::vec3> corners;
    for (int i = 0; i < frameUniforms.occluders; ++i) {
      const glm::vec3 c = frameUniforms.occCentre[i], r = frameUniforms.occRadii[i];
      if (std::abs(glm::dot(c - g.groundOrigin, n)) > 2.5f * glm::length(r * n)) continue;  // out of reach
      for (int k = 0; k < 8; ++k) {
        const glm::vec3 s((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f, (k & 4) ? 1.0f : -1.0f);
        const glm::vec3 p = c + 2.5f * s * r;
        corners.push_back(p - n * glm::dot(p - g.groundOrigin, n));
      }
    }
    if (corners.empty()) return glm::ivec4(0);
    return screenRect(corners, frameUniforms.viewProj, settings.width, settings.height, 2.0f);
  }

  // The sky on the far plane, after the opaque meshes: early depth testing leaves out every
  // pixel something covers (they would be shaded twice otherwise).
  // With the cached background it is there already.
  void skyPass() {
    if (fromBackground) return;
    drawSky();
    mark(RenderPass::Sky);
  }

  void drawSky() {
    glDepthMask(GL_FALSE);
    use(skyProg);
    skyProg.set("uTop", skyTop);
    skyProg.set("uBottom", skyBottom);
    skyProg.set("uHeight", static_cast<float>(settings.height));
    glBindVertexArray(emptyVao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
  }

  // Translucent meshes back to front (by their bounds' centres), blended (premultiplied alpha).
  // Of each only its nearest surface is drawn: a depth-only prepass of its front faces, then
  // the front faces where they are that nearest depth (LEQUAL). Its far side and its inner folds
  // never show through (a fan of bottom triangles would show as a star); how much of what is
  // behind shows is the shader's thickness-driven opacity.
  void translucentPass(bool shadowsOn) {
    if (translucent.empty()) return;
    auto dist = [&](const GpuMesh* m) { return glm::length(0.5f * (m->bounds.lo + m->bounds.hi) - camera.position); };
    std::sort(translucent.begin(), translucent.end(),
              [&](const GpuMesh* a, const GpuMesh* b) { return dist(a) > dist(b); });
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    for (const GpuMesh* m : translucent) {
      glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      glDepthMask(GL_TRUE);
      use(depthProg);
      depthProg.set("uLightViewProj", frameUniforms.viewProj);
      glBindVertexArray(m->vao);
      glDrawElements(GL_TRIANGLES, m->indexCount, GL_UNSIGNED_INT, nullptr);
      glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      glDepthMask(GL_FALSE);
      drawMesh(shadowsOn, *m);
      drawnOver(*m);
    }
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
    mark(RenderPass::Translucent);
  }

  // Anti-aliasing into the final framebuffer: the MSAA resolve or the FXAA pass (none for a
  // Plain target, which is the final framebuffer already).
  //
  // With the cached background, FXAA runs only where this frame may differ from the background's
  // own anti-aliased image, which is copied in first (where the last frame drew): within
  // kFxaaReach pixels of what the frame drew over it. FXAA reads a pixel's diagonal neighbours
  // and blends taps at most 4 pixels away (bilinear: 5), so every pixel farther out has the same
  // inputs, and output, as in the background's image.
  static constexpr int kFxaaReach = 6;
  void antiAliasPass() {
    glDisable(GL_DEPTH_TEST);
    ctx.resolve();
    if (fromBackground) sceneDirty = changedAll ? whole() : changed;
    if (ctx.target() == SceneTarget::PostProcess) {
      if (!fromBackground) {
        ctx.bindFinalTarget();
        fxaa(ctx.sceneTexture());
      } else {
        ctx.restoreBackgroundFinal(finalDirty.lo.x, finalDirty.lo.y, finalDirty.hi.x, finalDirty.hi.y);
        PixelRect r = whole();
        if (!changedAll) {
          r.lo = glm::max(changed.lo - kFxaaReach, r.lo);
          r.hi = glm::min(changed.hi + kFxaaReach, r.hi);
        }
        finalDirty = PixelRect{};
        if (!r.empty()) {
          glEnable(GL_SCISSOR_TEST);
          glScissor(r.lo.x, r.lo.y, r.hi.x - r.lo.x, r.hi.y - r.lo.y);
          fxaa(ctx.sceneTexture());
          glDisable(GL_SCISSOR_TEST);
          finalDirty = r;
        }
      }
    } else {
      ctx.bindFinalTarget();
    }
    if (ctx.target() != SceneTarget::Plain) mark(RenderPass::AntiAlias);
  }

  // FXAA of `source` into the bound target (within the scissor, if set). Leaves the depth test off.
  void fxaa(GLuint source) {
    glBindTexture(GL_TEXTURE_2D, source);
    glBindVertexArray(emptyVao);
    const glm::vec2 texel(1.0f / static_cast<float>(settings.width), 1.0f / static_cast<float>(settings.height));
    const auto fxaaPass = [&](Program& p) {
      use(p);
      p.set("uScene", 0);
      p.set("uTexel", texel);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    };
    // Every pixel's exact colour, and the edge pixels marked at depth 0 (the rest at 1).
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    glDepthMask(GL_TRUE);
    fxaaPass(fxaaEdgeProg);
    // The blend, at depth 0.5: passes only over the marked pixels.
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_FALSE);
    fxaaPass(fxaaProg);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LEQUAL);
    glDisable(GL_DEPTH_TEST);
  }

  // The overlay goes on last, over the anti-aliased frame (its text is already smooth).
  void overlayPass() {
    if (overlayW <= 0 || overlayH <= 0) return;
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    const float margin = std::max(4.0f, static_cast<float>(settings.height) / 90.0f);
    const float W = static_cast<float>(settings.width), H = static_cast<float>(settings.height);
    const float mx = std::round(margin), my = std::round(margin);
    if (fromBackground) {  // the frame's pixels the overlay covers (rounded outwards)
      const int x0 = static_cast<int>(mx), y1 = settings.height - static_cast<int>(my);
      (ctx.target() == SceneTarget::Plain ? sceneDirty : finalDirty)
          .add({{x0 - 1, y1 - overlayH - 1}, {x0 + overlayW + 1, y1 + 1}});
    }
    use(overlayProg);
    overlayProg.set("uRect", glm::vec4(-1.0f + 2.0f * mx / W, 1.0f - 2.0f * my / H,
                                       -1.0f + 2.0f * (mx + static_cast<float>(overlayW)) / W,
                                       1.0f - 2.0f * (my + static_cast<float>(overlayH)) / H));
    overlayProg.set("uTex", 0);
    glBindTexture(GL_TEXTURE_2D, overlayTex);
    glBindVertexArray(emptyVao);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glDisable(GL_BLEND);
    mark(RenderPass::Overlay);
  }

  // All GL work finished (glFinish), errors checked, the frame's time recorded.
  void endFrame(Clock::time_point t0) {
    glBindVertexArray(0);
    glFinish();
    const GLenum err = glGetError();
    if (err != GL_NO_ERROR) throw RenderError("Renderer::render: GL error 0x" + std::to_string(err));
    timings.renderMs = msSince(t0);
    timings.totalRenderMs += timings.renderMs;
    ++timings.frames;
  }
};

// ---------------------------------------------------------------- Renderer
Renderer::Renderer(const RenderSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
Renderer::~Renderer() = default;

float Renderer::aspect() const {
  return static_cast<float>(impl_->settings.width) / static_cast<float>(impl_->settings.height);
}

MeshId Renderer::addDynamicMesh(std::size_t vertexCount, std::span<const std::uint32_t> triangles,
                                const Material& material, bool refine) {
  impl_->ctx.makeCurrent();
  return impl_->createMesh(vertexCount, triangles, material, true, refine);
}

void Renderer::updateDynamicMesh(MeshId id, std::span<const float> positions, std::span<const std::uint8_t> flat) {
  impl_->ctx.makeCurrent();
  GpuMesh& m = impl_->mesh(id);
  if (!m.dynamic) throw RenderError("Renderer: mesh " + std::to_string(id) + " is not dynamic");
  const auto t0 = Clock::now();
  if (!flat.empty() && flat.size() != m.vertexCount)
    throw RenderError("Renderer: got " + std::to_string(flat.size()) + " flat flags for " +
                      std::to_string(m.vertexCount) + " vertices");
  impl_->setPositions(m, positions, flat);
  if (impl_->settings.profilePasses) {
    glFinish();
    impl_->timings.passMs[static_cast<std::size_t>(RenderPass::Upload)] += msSince(t0);
  }
}

MeshId Renderer::addStaticMesh(std::span<const float> positions,
                               std::span<const std::uint32_t> triangles, const Material& material) {
  if (positions.size() % 3 != 0)
    throw RenderError("Renderer: position count " + std::to_string(positions.size()) +
                      " is not a multiple of 3");
  impl_->ctx.makeCurrent();
  const MeshId id = impl_->createMesh(positions.size() / 3, triangles, material, false);
  impl_->setPositions(impl_->meshes[id], positions);
  return id;
}

MeshId Renderer::addStaticMesh(const MeshData& mesh, const Material& material) {
  return addStaticMesh(mesh.positions, mesh.indices, material);
}

namespace {
constexpr int kGroundCells = 16;
// A ground's grid vertices: (cells + 1)^2 points of the square through `point` spanned by u, v.
std::vector<float> groundGrid(glm::vec3 point, glm::vec3 u, glm::vec3 v, float halfExtent) {
  std::vector<float> positions;
  positions.reserve(3 * (kGroundCells + 1) * (kGroundCells + 1));
  for (int j = 0; j <= kGroundCells; ++j)
    for (int i = 0; i <= kGroundCells; ++i) {
      const float a = (2.0f * static_cast<float>(i) / kGroundCells - 1.0f) * halfExtent;
      const float b = (2.0f * static_cast<float>(j) / kGroundCells - 1.0f) * halfExtent;
      const glm::vec3 p = point + a * u + b * v;
      positions.insert(positions.end(), {p.x, p.y, p.z});
    }
  return positions;
}
}  // namespace

MeshId Renderer::addGround(glm::vec3 point, glm::vec3 normal, float halfExtent, glm::vec3 colourA,
                           glm::vec3 colourB, float tileSize) {
  if (!(halfExtent > 0.0f) || !(tileSize > 0.0f) || !(glm::length(normal) > 0.0f))
    throw RenderError("Renderer::addGround: extent, tile size and normal must be non-zero");
  const glm::vec3 n = glm::normalize(normal);
  const glm::vec3 helper = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
  const glm::vec3 u = glm::normalize(glm::cross(n, glm::cross(helper, n)));
  const glm::vec3 v = glm::cross(u, n);  // u x v = n... (u, n, v) keeps CCW seen from +n below
  // A grid rather than one quad keeps the depth interpolation and fog smooth.
  MeshData grid;
  const int cells = kGroundCells;
  grid.positions = groundGrid(point, u, v, halfExtent);
  for (std::uint32_t j = 0; j < cells; ++j)
    for (std::uint32_t i = 0; i < cells; ++i) {
      const std::uint32_t k = j * (cells + 1) + i;
      // Orientation chosen so the face normal is +n (checked below).
      grid.indices.insert(grid.indices.end(), {k, k + cells + 1, k + 1, k + 1, k + cells + 1, k + cells + 2});
    }
  {
    const glm::vec3 p0(grid.positions[0], grid.positions[1], grid.positions[2]);
    const glm::vec3 p1(grid.positions[3 * (cells + 1)], grid.positions[3 * (cells + 1) + 1],
                       grid.positions[3 * (cells + 1) + 2]);
    const glm::vec3 p2(grid.positions[3], grid.positions[4], grid.positions[5]);
    if (glm::dot(glm::cross(p1 - p0, p2 - p0), n) < 0.0f)
      for (std::size_t t = 0; t < grid.indices.size(); t += 3) std::swap(grid.indices[t + 1], grid.indices[t + 2]);
  }
  Material mat;
  mat.colour = colourA;
  mat.specular = 0.0f;
  const MeshId id = addStaticMesh(grid, mat);
  GpuMesh& m = impl_->meshes[id];
  m.ground = true;
  m.groundOrigin = point;
  m.groundU = u;
  m.groundV = v;
  m.groundRestU = u;
  m.groundRestV = v;
  m.groundB = colourB;
  m.tile = tileSize;
  m.extent = halfExtent;
  return id;
}

void Renderer::placeGround(MeshId id, glm::vec3 point, const glm::mat3& rotation) {
  impl_->ctx.makeCurrent();
  GpuMesh& m = impl_->mesh(id);
  if (!m.ground) throw RenderError("Renderer: mesh " + std::to_string(id) + " is not a ground");
  m.groundOrigin = point;
  m.groundU = rotation * m.groundRestU;
  m.groundV = rotation * m.groundRestV;
  impl_->setPositions(m, groundGrid(point, m.groundU, m.groundV, m.extent));
}

void Renderer::setCamera(const Camera& camera) {
  (void)camera.view();  // a degenerate camera (position == target) throws here, not mid-frame
  impl_->camera = camera;
}
void Renderer::setLight(const Light& light) {
  if (!(glm::length(light.direction) > 0.0f))
    throw RenderError("Renderer::setLight: zero light direction");
  impl_->light = light;
}
void Renderer::setSky(glm::vec3 top, glm::vec3 bottom) {
  impl_->skyTop = top;
  impl_->skyBottom = bottom;
}
void Renderer::setOverlayText(std::vector<std::string> lines) {
  if (lines == impl_->overlayLines) return;
  impl_->overlayLines = std::move(lines);
  impl_->overlayDirty = true;
}

void Renderer::render() { impl_->render(); }

const char* passName(RenderPass pass) {
  switch (pass) {
    case RenderPass::Upload: return "upload";
    case RenderPass::Shadow: return "shadow map";
    case RenderPass::Background: return "background";
    case RenderPass::Sky: return "sky";
    case RenderPass::Opaque: return "opaque meshes";
    case RenderPass::Ground: return "ground";
    case RenderPass::Translucent: return "translucent meshes";
    case RenderPass::AntiAlias: return "anti-aliasing";
    case RenderPass::Overlay: return "overlay";
    case RenderPass::Count: break;
  }
  return "?";
}

void Renderer::readPixels(std::vector<std::uint8_t>& rgba, RowOrder order) {
  const auto t0 = Clock::now();
  impl_->ctx.makeCurrent();
  impl_->ctx.readPixels(rgba, order == RowOrder::TopDown);
  impl_->timings.readbackMs = msSince(t0);
  impl_->timings.totalReadbackMs += impl_->timings.readbackMs;
  ++impl_->timings.readbacks;
}

Image Renderer::readImage() {
  Image img;
  img.width = impl_->settings.width;
  img.height = impl_->settings.height;
  readPixels(img.rgba);
  return img;
}

const RenderTimings& Renderer::timings() const { return impl_->timings; }

std::string Renderer::glInfo() const {
  return std::string(impl_->ctx.glRenderer()) + " / " + impl_->ctx.glVersion();
}

}  // namespace springy::render

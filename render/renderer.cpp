#include "render/renderer.hpp"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>

#include "render/error.hpp"
#include "render/gl_context.hpp"

namespace springy::render {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// ---------------------------------------------------------------- shaders
constexpr const char* kMeshVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
uniform mat4 uViewProj;
invariant gl_Position;  // the ground is drawn by two variants and must land on the same depths
uniform mat4 uLightViewProj;
uniform float uNormalOffset;
out vec3 vPos;
out vec3 vNormal;
out vec4 vLightPos;
void main() {
  vPos = aPos;
  vNormal = aNormal;
  // Normal offset: look the shadow map up slightly off the surface (less acne).
  vLightPos = uLightViewProj * vec4(aPos + aNormal * uNormalOffset, 1.0);
  gl_Position = uViewProj * vec4(aPos, 1.0);
}
)";

// Compiled in variants (see meshVariantSource): SHADOWS, GROUND and FLAT are preprocessor
// switches, so a fragment only runs the code its mesh needs (llvmpipe executes both sides of a
// branch, even on a uniform).
constexpr const char* kMeshFsBody = R"(
in vec3 vPos;
in vec3 vNormal;
in vec4 vLightPos;
uniform vec3 uAlbedo;       // linear colour (ground: colour A)
uniform float uAlpha;
uniform float uShininess;
uniform float uSpecular;
uniform vec3 uToLight;      // unit vector towards the light
uniform vec3 uLightColour;
uniform vec3 uAmbient;
uniform vec3 uEye;
uniform sampler2DShadow uShadowMap;
uniform float uShadowStep;  // PCF tap spacing, shadow-map uv units
uniform vec3 uGroundOrigin;
uniform vec3 uGroundU;
uniform vec3 uGroundV;
uniform vec3 uGroundB;      // linear colour B
uniform float uTile;
uniform float uGroundExtent;
uniform vec3 uSkyTop;
uniform vec3 uSkyBottom;
uniform float uHeight;
out vec4 fragColour;

vec3 toDisplay(vec3 c) { return pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)); }

#if SHADOWS
float shadowFactor() {
  vec3 p = vLightPos.xyz / vLightPos.w * 0.5 + 0.5;
  if (p.x <= 0.0 || p.x >= 1.0 || p.y <= 0.0 || p.y >= 1.0) return 1.0;
  p.z = min(p.z, 1.0);  // receivers beyond the far plane compare as "far"
  // 4 bilinear (hardware 2x2) comparisons = smooth 4x4-texel penumbra.
  float s = texture(uShadowMap, vec3(p.xy + vec2(-uShadowStep, -uShadowStep), p.z));
  s += texture(uShadowMap, vec3(p.xy + vec2(uShadowStep, -uShadowStep), p.z));
  s += texture(uShadowMap, vec3(p.xy + vec2(-uShadowStep, uShadowStep), p.z));
  s += texture(uShadowMap, vec3(p.xy + vec2(uShadowStep, uShadowStep), p.z));
  return s * 0.25;
}
#endif

void main() {
#if FLAT
  // Faceted: the screen-space derivatives of the position span the triangle's plane; their
  // cross product faces the viewer.
  vec3 n = normalize(cross(dFdx(vPos), dFdy(vPos)));
#else
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing) n = -n;  // two-sided lighting
#endif
  vec3 l = uToLight;
  float ndl = max(dot(n, l), 0.0);
#if SHADOWS
  float shadow = ndl > 0.0 ? shadowFactor() : 1.0;
#else
  float shadow = 1.0;
#endif
  float hemi = 0.75 + 0.25 * n.y;
#if GROUND
  vec3 d = vPos - uGroundOrigin;
  vec2 uv = vec2(dot(d, uGroundU), dot(d, uGroundV)) / uTile;
  // Box-filtered checker: averages to grey where tiles get smaller than a pixel.
  vec2 w = fwidth(uv) + 1e-4;
  vec2 i = 2.0 * (abs(fract((uv - 0.5 * w) * 0.5) - 0.5) - abs(fract((uv + 0.5 * w) * 0.5) - 0.5)) / w;
  vec3 albedo = mix(uAlbedo, uGroundB, 0.5 - 0.5 * i.x * i.y);
  float fog = smoothstep(0.55, 1.0, length(d) / uGroundExtent);
  vec3 lit = albedo * (uAmbient * hemi + uLightColour * ndl * shadow);
  // The ground fades into the sky towards its edge: the sky's colour at this pixel (as the sky
  // pass draws it), mixed in here, so the sky is only drawn where nothing else is.
  float t = clamp((gl_FragCoord.y - 0.5) / max(uHeight - 1.0, 1.0), 0.0, 1.0);
  fragColour = vec4(mix(toDisplay(lit), mix(uSkyBottom, uSkyTop, t), fog), uAlpha);
#else
  vec3 v = normalize(uEye - vPos);
  vec3 h = normalize(l + v);
  float spec = ndl > 0.0 ? uSpecular * pow(max(dot(n, h), 0.0), uShininess) : 0.0;
  vec3 lit = uAlbedo * (uAmbient * hemi + uLightColour * ndl * shadow) + uLightColour * spec * shadow;
  fragColour = vec4(toDisplay(lit), uAlpha);
#endif
}
)";

std::string meshVariantSource(bool shadows, bool ground, bool flat) {
  return std::string("#version 330 core\n#define SHADOWS ") + (shadows ? "1" : "0") +
         "\n#define GROUND " + (ground ? "1" : "0") + "\n#define FLAT " + (flat ? "1" : "0") +
         "\n" + kMeshFsBody;
}

// FXAA-style anti-aliasing (after Lottes' FXAA, "console" variant): the luma of the 4 diagonal
// neighbours gives the edge direction; two and four taps along the edge are blended; pixels
// whose neighbourhood contrast is low keep their exact colour (texelFetch). Two passes, because
// llvmpipe runs both sides of a branch: EDGE_PASS writes every pixel's exact colour and marks
// the edge pixels in the depth buffer (depth 0, the rest 1); the blend pass, drawn at depth 0.5
// with GL_GREATER, then runs only where an edge was marked (early depth test).
constexpr const char* kFxaaFsBody = R"(
uniform sampler2D uScene;
uniform vec2 uTexel;  // 1 / frame size
out vec4 fragColour;
float luma(vec3 c) { return dot(c, vec3(0.299, 0.587, 0.114)); }
void main() {
  ivec2 ip = ivec2(gl_FragCoord.xy);
  ivec2 hi = textureSize(uScene, 0) - 1;
  vec3 rgbM = texelFetch(uScene, ip, 0).rgb;
  float lNW = luma(texelFetch(uScene, clamp(ip + ivec2(-1, -1), ivec2(0), hi), 0).rgb);
  float lNE = luma(texelFetch(uScene, clamp(ip + ivec2(1, -1), ivec2(0), hi), 0).rgb);
  float lSW = luma(texelFetch(uScene, clamp(ip + ivec2(-1, 1), ivec2(0), hi), 0).rgb);
  float lSE = luma(texelFetch(uScene, clamp(ip + ivec2(1, 1), ivec2(0), hi), 0).rgb);
  float lM = luma(rgbM);
  float lMin = min(lM, min(min(lNW, lNE), min(lSW, lSE)));
  float lMax = max(lM, max(max(lNW, lNE), max(lSW, lSE)));
  bool edge = !(lMax - lMin < max(0.0312, lMax * 0.125));
#if EDGE_PASS
  fragColour = vec4(rgbM, 1.0);  // no edge here: the exact colour
  gl_FragDepth = edge ? 0.0 : 1.0;
#else
  if (!edge) {
    fragColour = vec4(rgbM, 1.0);
    return;
  }
  vec2 uv = gl_FragCoord.xy * uTexel;
  vec2 dir = vec2(-((lNW + lNE) - (lSW + lSE)), (lNW + lSW) - (lNE + lSE));
  float reduce = max((lNW + lNE + lSW + lSE) * (0.25 / 8.0), 1.0 / 128.0);
  float rcpDirMin = 1.0 / (min(abs(dir.x), abs(dir.y)) + reduce);
  dir = clamp(dir * rcpDirMin, vec2(-8.0), vec2(8.0)) * uTexel;
  vec3 rgbA = 0.5 * (textureLod(uScene, uv + dir * (1.0 / 3.0 - 0.5), 0.0).rgb +
                     textureLod(uScene, uv + dir * (2.0 / 3.0 - 0.5), 0.0).rgb);
  vec3 rgbB = rgbA * 0.5 + 0.25 * (textureLod(uScene, uv - dir * 0.5, 0.0).rgb +
                                   textureLod(uScene, uv + dir * 0.5, 0.0).rgb);
  float lB = luma(rgbB);
  fragColour = vec4((lB < lMin || lB > lMax) ? rgbA : rgbB, 1.0);
#endif
}
)";
std::string fxaaSource(bool edgePass) {
  return std::string("#version 330 core\n#define EDGE_PASS ") + (edgePass ? "1" : "0") + "\n" + kFxaaFsBody;
}

constexpr const char* kDepthVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
uniform mat4 uLightViewProj;
void main() { gl_Position = uLightViewProj * vec4(aPos, 1.0); }
)";
constexpr const char* kDepthFs = R"(#version 330 core
void main() {}
)";

constexpr const char* kSkyVs = R"(#version 330 core
void main() {
  // One triangle covering the screen.
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 1.0, 1.0);  // on the far plane: depth 1, behind everything
}
)";
// One triangle covering the screen at depth 0.5 (the FXAA blend pass).
constexpr const char* kMidVs = R"(#version 330 core
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";
constexpr const char* kSkyFs = R"(#version 330 core
uniform vec3 uTop;
uniform vec3 uBottom;
uniform float uHeight;
out vec4 fragColour;
void main() {
  float t = clamp((gl_FragCoord.y - 0.5) / max(uHeight - 1.0, 1.0), 0.0, 1.0);
  fragColour = vec4(mix(uBottom, uTop, t), 1.0);
}
)";

constexpr const char* kOverlayVs = R"(#version 330 core
uniform vec4 uRect;  // NDC x0, y0 (top), x1, y1 (bottom)
out vec2 vUv;
void main() {
  vec2 c = vec2((gl_VertexID & 1) != 0 ? 1.0 : 0.0, (gl_VertexID & 2) != 0 ? 1.0 : 0.0);
  vUv = c;  // v = 0: first (top) texture row
  gl_Position = vec4(mix(uRect.x, uRect.z, c.x), mix(uRect.y, uRect.w, c.y), 0.0, 1.0);
}
)";
constexpr const char* kOverlayFs = R"(#version 330 core
in vec2 vUv;
uniform sampler2D uTex;
out vec4 fragColour;
void main() { fragColour = texture(uTex, vUv); }  // premultiplied alpha
)";

GLuint compile(GLenum type, const char* src, const char* what) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw RenderError(std::string("Renderer: ") + what + " shader failed to compile: " + log);
  }
  return s;
}

class Program {
public:
  Program() = default;
  Program(const char* vs, const char* fs, const char* what) {
    const GLuint v = compile(GL_VERTEX_SHADER, vs, what);
    GLuint f = 0;
    try {
      f = compile(GL_FRAGMENT_SHADER, fs, what);
    } catch (...) {
      glDeleteShader(v);
      throw;
    }
    id_ = glCreateProgram();
    glAttachShader(id_, v);
    glAttachShader(id_, f);
    glLinkProgram(id_);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(id_, GL_LINK_STATUS, &ok);
    if (!ok) {
      GLint len = 0;
      glGetProgramiv(id_, GL_INFO_LOG_LENGTH, &len);
      std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
      glGetProgramInfoLog(id_, len, nullptr, log.data());
      throw RenderError(std::string("Renderer: ") + what + " program failed to link: " + log);
    }
  }
  ~Program() {
    if (id_) glDeleteProgram(id_);
  }
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
  Program(Program&& o) noexcept : id_(std::exchange(o.id_, 0u)), locs_(std::move(o.locs_)) {}
  Program& operator=(Program&& o) noexcept {
    std::swap(id_, o.id_);
    std::swap(locs_, o.locs_);
    return *this;
  }
  void use() const { glUseProgram(id_); }
  GLint loc(const char* name) {
    auto it = locs_.find(name);
    if (it != locs_.end()) return it->second;
    const GLint l = glGetUniformLocation(id_, name);
    locs_.emplace(name, l);
    return l;
  }
  void set(const char* n, int v) { glUniform1i(loc(n), v); }
  void set(const char* n, float v) { glUniform1f(loc(n), v); }
  void set(const char* n, glm::vec2 v) { glUniform2fv(loc(n), 1, glm::value_ptr(v)); }
  void set(const char* n, glm::vec3 v) { glUniform3fv(loc(n), 1, glm::value_ptr(v)); }
  void set(const char* n, glm::vec4 v) { glUniform4fv(loc(n), 1, glm::value_ptr(v)); }
  void set(const char* n, const glm::mat4& m) {
    glUniformMatrix4fv(loc(n), 1, GL_FALSE, glm::value_ptr(m));
  }

private:
  GLuint id_ = 0;
  std::unordered_map<std::string, GLint> locs_;
};

struct Bounds {
  glm::vec3 lo{std::numeric_limits<float>::max()};
  glm::vec3 hi{std::numeric_limits<float>::lowest()};
  bool empty() const { return lo.x > hi.x; }
  void add(glm::vec3 p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void add(const Bounds& b) {
    if (!b.empty()) add(b.lo), add(b.hi);
  }
};

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei indexCount = 0;
  std::size_t vertexCount = 0;
  std::vector<std::uint32_t> indices;  // kept for normal recomputation
  std::vector<float> interleaved;      // position + normal per vertex
  Material material;
  Bounds bounds;
  bool dynamic = false;
  bool hasPositions = false;
  // Ground only:
  bool ground = false;
  glm::vec3 groundOrigin{0.0f}, groundU{1, 0, 0}, groundV{0, 0, 1}, groundB{0.5f};
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

}  // namespace

// ---------------------------------------------------------------- Impl
struct Renderer::Impl {
  RenderSettings settings;
  GlContext ctx;
  // Mesh shader variants, compiled on first use: index = shadows | ground << 1 | flat << 2.
  std::optional<Program> meshProgs[8];
  Program depthProg, skyProg, overlayProg, fxaaEdgeProg, fxaaProg;
  // Per frame: which mesh variants got this frame's shared uniforms, and what they are.
  unsigned framePrepared = 0;
  struct FrameUniforms {
    glm::mat4 viewProj{1.0f}, lightVP{1.0f};
    float normalOffset = 0.0f;
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
                    const Material& mat, bool dynamic) {
    checkTriangles(tris, vertexCount);
    GpuMesh m;
    m.vertexCount = vertexCount;
    m.indices.assign(tris.begin(), tris.end());
    m.indexCount = static_cast<GLsizei>(tris.size());
    m.material = mat;
    m.dynamic = dynamic;
    m.interleaved.assign(vertexCount * 6, 0.0f);
    glGenVertexArrays(1, &m.vao);
    glGenBuffers(1, &m.vbo);
    glGenBuffers(1, &m.ebo);
    glBindVertexArray(m.vao);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(m.interleaved.size() * sizeof(float)),
                 nullptr, dynamic ? GL_STREAM_DRAW : GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(m.indices.size() * sizeof(std::uint32_t)),
                 m.indices.data(), GL_STATIC_DRAW);
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

  // Area-weighted smooth normals, interleaved with positions, uploaded to the VBO.
  void setPositions(GpuMesh& m, std::span<const float> pos) {
    if (pos.size() != m.vertexCount * 3)
      throw RenderError("Renderer: got " + std::to_string(pos.size()) + " position floats for " +
                        std::to_string(m.vertexCount) + " vertices");
    std::vector<glm::vec3> normals(m.vertexCount, glm::vec3(0.0f));
    auto P = [&](std::uint32_t i) {
      return glm::vec3(pos[3 * std::size_t{i}], pos[3 * std::size_t{i} + 1], pos[3 * std::size_t{i} + 2]);
    };
    for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      const std::uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
      const glm::vec3 pa = P(a);
      const glm::vec3 n = glm::cross(P(b) - pa, P(c) - pa);  // |n| = 2 * area
      normals[a] += n;
      normals[b] += n;
      normals[c] += n;
    }
    Bounds b;
    for (std::size_t i = 0; i < m.vertexCount; ++i) {
      const glm::vec3 p(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
      b.add(p);
      const float len = glm::length(normals[i]);
      const glm::vec3 n = len > 0.0f && std::isfinite(len) ? normals[i] / len : glm::vec3(0, 1, 0);
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

  // Shadow map texels needed for light-space extent `size` (world units): at the casters'
  // nearest point to the camera, a texel should cover at most one pixel (the PCF taps blur over
  // 4 texels anyway; the bounds' corners overestimate a round caster). A power of two in
  // 256..shadowMapSize; shadowMapSize when fitting is off.
  int fittedShadowSize(const Bounds& b, float size) const {
    if (!settings.fitShadowMap) return settings.shadowMapSize;
    const glm::vec3 centre = 0.5f * (b.lo + b.hi);
    const float radius = 0.5f * glm::length(b.hi - b.lo);
    const float distance = std::max(glm::length(centre - camera.position) - radius, camera.nearPlane);
    const float pixelsPerUnit = static_cast<float>(settings.height) /
                                (2.0f * distance * std::tan(glm::radians(0.5f * camera.fovYDeg)));
    const float texels = size * pixelsPerUnit;
    int n = 256;
    while (n < settings.shadowMapSize && static_cast<float>(n) < texels) n *= 2;
    return std::min(n, settings.shadowMapSize);
  }

  void resizeShadowMap(int n) {
    if (n == shadowSize) return;
    glBindTexture(GL_TEXTURE_2D, shadowTex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, n, n, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
    glBindTexture(GL_TEXTURE_2D, 0);
    shadowSize = n;
  }

  // Orthographic light frustum around the caster bounds, snapped so that shadows do not shimmer
  // when the bounds change a little from frame to frame. Sizes the shadow map to fit.
  glm::mat4 lightViewProj(const Bounds& b, float& texelWorld) {
    const glm::vec3 d = glm::normalize(light.direction);
    const float radius = std::max(0.5f * glm::length(b.hi - b.lo), 1e-3f);
    const glm::vec3 up = std::abs(d.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
    // View matrix at the origin-aligned light basis (translation-free, so snapping is stable).
    const glm::mat4 view = glm::lookAt(glm::vec3(0.0f), d, up);
    Bounds ls;
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y,
                             (i & 4) ? b.hi.z : b.lo.z);
      ls.add(glm::vec3(view * glm::vec4(corner, 1.0f)));
    }
    const float pad = 0.05f * radius + 1e-3f;
    float size = std::max(ls.hi.x - ls.lo.x, ls.hi.y - ls.lo.y) + 2.0f * pad;
    size = std::exp2(std::ceil(std::log2(size) * 8.0f) / 8.0f);  // 1/8-octave steps
    resizeShadowMap(fittedShadowSize(b, size));
    const float texel = size / static_cast<float>(shadowSize);
    glm::vec2 mid(0.5f * (ls.lo.x + ls.hi.x), 0.5f * (ls.lo.y + ls.hi.y));
    mid = glm::floor(mid / texel) * texel;
    texelWorld = texel;
    const float nearZ = -ls.hi.z - pad, farZ = -ls.lo.z + pad;
    const glm::mat4 proj = glm::ortho(mid.x - 0.5f * size, mid.x + 0.5f * size, mid.y - 0.5f * size,
                                      mid.y + 0.5f * size, nearZ, farZ);
    return proj * view;
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

  Program& meshProgram(bool shadowsOn, const GpuMesh& m) {
    const unsigned key = (shadowsOn ? 1u : 0u) | (m.ground ? 2u : 0u) | (m.material.flat && !m.ground ? 4u : 0u);
    std::optional<Program>& p = meshProgs[key];
    if (!p) {
      const std::string fs = meshVariantSource(key & 1u, key & 2u, key & 4u);
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
      p->set("uAmbient", light.ambient);
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

  // The screen rectangle (x, y, width, height; empty when off screen) that holds every pixel of
  // ground g the shadow map covers: the light frustum's sides, followed along the light onto the
  // ground's plane, projected by the camera. None (shade all of it with shadows) when the light
  // grazes the plane or a corner lies behind the camera.
  std::optional<glm::ivec4> shadowFootprint(const GpuMesh& g) const {
    const glm::vec3 n = glm::normalize(glm::cross(g.groundU, g.groundV));
    const glm::vec3 d = glm::normalize(light.direction);
    const float along = glm::dot(d, n);
    if (std::abs(along) < 0.05f) return std::nullopt;
    const glm::mat4 toWorld = glm::inverse(frameUniforms.lightVP);
    glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (int k = 0; k < 4; ++k) {
      const glm::vec4 w = toWorld * glm::vec4((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f, -1.0f, 1.0f);
      const glm::vec3 c = glm::vec3(w) / w.w;
      const glm::vec3 onPlane = c + d * (glm::dot(g.groundOrigin - c, n) / along);
      const glm::vec4 clip = frameUniforms.viewProj * glm::vec4(onPlane, 1.0f);
      if (!(clip.w > 1e-4f)) return std::nullopt;
      const glm::vec2 ndc = glm::vec2(clip) / clip.w;
      lo = glm::min(lo, ndc);
      hi = glm::max(hi, ndc);
    }
    // Pixels, widened by 4: the normal offset and the filter taps reach a little past the sides.
    const glm::vec2 size(static_cast<float>(settings.width), static_cast<float>(settings.height));
    const glm::vec2 pLo = glm::clamp((lo * 0.5f + 0.5f) * size - 4.0f, glm::vec2(0.0f), size);
    const glm::vec2 pHi = glm::clamp((hi * 0.5f + 0.5f) * size + 4.0f, glm::vec2(0.0f), size);
    const glm::ivec2 a(glm::floor(pLo)), b(glm::ceil(pHi));
    return glm::ivec4(a.x, a.y, std::max(b.x - a.x, 0), std::max(b.y - a.y, 0));
  }

  static glm::vec3 toLinear(glm::vec3 c) { return glm::pow(glm::max(c, glm::vec3(0.0f)), glm::vec3(2.2f)); }

  // layerAlpha: a translucent body is drawn as two layers (inside, then outside); each gets the
  // alpha that makes the pair as opaque as material.alpha: 1 - (1 - a')^2 = a.
  void drawMesh(bool shadowsOn, const GpuMesh& m, bool twoLayers = false) {
    Program& p = meshProgram(shadowsOn, m);
    const float alpha = std::clamp(m.material.alpha, 0.0f, 1.0f);
    p.set("uAlbedo", toLinear(m.material.colour));
    p.set("uAlpha", twoLayers ? 1.0f - std::sqrt(1.0f - alpha) : alpha);
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

  void render() {
    const auto t0 = Clock::now();
    passStart = t0;
    ctx.makeCurrent();
    current = nullptr;
    framePrepared = 0;
    if (overlayDirty) rebuildOverlay();
    const float aspect = static_cast<float>(settings.width) / static_cast<float>(settings.height);

    // Shadow pass.
    glm::mat4 lightVP(1.0f);
    float texelWorld = 0.0f;
    bool shadowsOn = false;
    if (settings.shadows) {
      const Bounds b = casterBounds();
      if (!b.empty()) {
        shadowsOn = true;
        lightVP = lightViewProj(b, texelWorld);
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
        depthProg.set("uLightViewProj", lightVP);
        for (const GpuMesh& m : meshes) {
          if (!drawable(m) || m.ground) continue;
          glBindVertexArray(m.vao);
          glDrawElements(GL_TRIANGLES, m.indexCount, GL_UNSIGNED_INT, nullptr);
        }
        glDisable(GL_POLYGON_OFFSET_FILL);
        mark(RenderPass::Shadow);
      }
    }
    frameUniforms.viewProj = camera.viewProjection(aspect);
    frameUniforms.lightVP = lightVP;
    frameUniforms.normalOffset = 1.5f * texelWorld;

    // Main pass: opaque meshes, grounds, sky, translucent meshes back to front.
    ctx.bindDrawTarget();
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, shadowTex);
    std::vector<const GpuMesh*> translucent, grounds;
    for (const GpuMesh& m : meshes) {
      if (!drawable(m)) continue;
      if (m.ground) grounds.push_back(&m);
      else if (m.material.alpha < 1.0f) translucent.push_back(&m);
      else drawMesh(shadowsOn, m);
    }
    mark(RenderPass::Opaque);
    // Grounds (opaque: they mix the sky colour into their faded edge themselves). A ground
    // receives the shadow map only where the map reaches it: llvmpipe runs the shadow taps for
    // every pixel the shadowing variant shades, also where they return "lit". So each ground is
    // drawn without them, then again with them inside the screen rectangle around that
    // footprint (the same vertices and depths: LEQUAL passes exactly where it was drawn); the
    // image is the same.
    if (!grounds.empty()) {
      for (const GpuMesh* g : grounds) {
        const std::optional<glm::ivec4> rect = shadowsOn ? shadowFootprint(*g) : std::nullopt;
        if (!rect) {
          drawMesh(shadowsOn, *g);
          continue;
        }
        drawMesh(false, *g);
        if ((*rect)[2] <= 0 || (*rect)[3] <= 0) continue;  // the footprint is off screen
        glEnable(GL_SCISSOR_TEST);
        glScissor((*rect)[0], (*rect)[1], (*rect)[2], (*rect)[3]);
        drawMesh(true, *g);
        glDisable(GL_SCISSOR_TEST);
      }
      mark(RenderPass::Ground);
    }
    // The sky on the far plane, after the opaque meshes: early depth testing leaves out every
    // pixel something covers (they would be shaded twice otherwise).
    glDepthMask(GL_FALSE);
    use(skyProg);
    skyProg.set("uTop", skyTop);
    skyProg.set("uBottom", skyBottom);
    skyProg.set("uHeight", static_cast<float>(settings.height));
    glBindVertexArray(emptyVao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
    mark(RenderPass::Sky);
    if (!translucent.empty()) {
      auto dist = [&](const GpuMesh* m) {
        return glm::length(0.5f * (m->bounds.lo + m->bounds.hi) - camera.position);
      };
      std::sort(translucent.begin(), translucent.end(),
                [&](const GpuMesh* a, const GpuMesh* b) { return dist(a) > dist(b); });
      glEnable(GL_BLEND);
      glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
      glDepthMask(GL_FALSE);
      glEnable(GL_CULL_FACE);
      for (const GpuMesh* m : translucent) {
        glCullFace(GL_FRONT);  // inside (far) faces first, then the near ones
        drawMesh(shadowsOn, *m, true);
        glCullFace(GL_BACK);
        drawMesh(shadowsOn, *m, true);
      }
      glDisable(GL_CULL_FACE);
      glDepthMask(GL_TRUE);
      mark(RenderPass::Translucent);
    }

    // Anti-aliasing into the final framebuffer: MSAA resolve or the FXAA pass.
    glDisable(GL_DEPTH_TEST);
    ctx.resolve();
    ctx.bindFinalTarget();
    if (ctx.target() == SceneTarget::PostProcess) {
      glBindTexture(GL_TEXTURE_2D, ctx.sceneTexture());
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
    if (ctx.target() != SceneTarget::Plain) mark(RenderPass::AntiAlias);

    // The overlay goes on last, over the anti-aliased frame (its text is already smooth).
    if (overlayW > 0 && overlayH > 0) {
      glEnable(GL_BLEND);
      glBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
      const float margin = std::max(4.0f, static_cast<float>(settings.height) / 90.0f);
      const float W = static_cast<float>(settings.width), H = static_cast<float>(settings.height);
      const float mx = std::round(margin), my = std::round(margin);
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
                                const Material& material) {
  impl_->ctx.makeCurrent();
  return impl_->createMesh(vertexCount, triangles, material, true);
}

void Renderer::updateDynamicMesh(MeshId id, std::span<const float> positions) {
  impl_->ctx.makeCurrent();
  GpuMesh& m = impl_->mesh(id);
  if (!m.dynamic) throw RenderError("Renderer: mesh " + std::to_string(id) + " is not dynamic");
  const auto t0 = Clock::now();
  impl_->setPositions(m, positions);
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
  const int cells = 16;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) {
      const float a = (2.0f * static_cast<float>(i) / cells - 1.0f) * halfExtent;
      const float b = (2.0f * static_cast<float>(j) / cells - 1.0f) * halfExtent;
      const glm::vec3 p = point + a * u + b * v;
      grid.positions.insert(grid.positions.end(), {p.x, p.y, p.z});
    }
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
  m.groundB = colourB;
  m.tile = tileSize;
  m.extent = halfExtent;
  return id;
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

// Why: the app turns simulation state into plain draw data (positions, triangles, colours) and
// asks for frames; Renderer owns all GL state for that: an offscreen GlContext, meshes, a
// camera, one shadow-casting directional light, a sky gradient, a checker ground, translucency
// and an overlay text block. It knows nothing about the simulation.
//
// Threading: a Renderer and its GL context belong to the thread that created it.
// Colours are display (sRGB) values in 0..1; lighting is done in linear light, then the tone
// curve and the sRGB encoding (look.h) give the display value, inside the shading pass.
#pragma once
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "render/camera.h"
#include "render/mesh_builders.h"
#include "render/row_order.h"
#include "render/text.h"

namespace springy::render {

struct Material {
  glm::vec3 colour{0.8f, 0.3f, 0.2f};  // display colour, 0..1
  // < 1: translucent, shaded as gelatine (e.g. jelly 0.7): drawn after opaque meshes, back to
  // front; only its nearest surface (front faces: wind triangles counter-clockwise from
  // outside); it blocks `alpha` of what is behind where it is 0.7 of its thickness (n.v = 0.7),
  // less at its thin rim, more through its middle; wrap diffuse, light through thin parts,
  // specular at least 0.9 and a Fresnel rim.
  float alpha = 1.0f;
  float shininess = 32.0f;   // Blinn-Phong exponent
  float specular = 0.25f;    // highlight strength, 0 = matte
  bool flat = false;         // faceted shading (a cube's faces) instead of smooth normals
};

// One directional light. direction: the way the light travels (e.g. (0,-1,0) = straight down).
struct Light {
  glm::vec3 direction{-0.35f, -1.0f, -0.45f};
  glm::vec3 colour{0.9f, 0.88f, 0.82f};  // linear intensity of the direct light
  // Linear ambient: from above tinted by the sky's top colour, from below half as strong, tinted
  // by the ground's colour (a hemisphere light).
  glm::vec3 ambient{0.28f, 0.30f, 0.34f};
};

// How edges are anti-aliased when RenderSettings::antiAlias is on.
//  Fxaa  post-process (FXAA-style: luma-edge detection, blend along the edge); one full-screen
//        pass on a single-sample frame. On llvmpipe several times cheaper than MSAA.
//  Msaa4 4 samples per pixel, resolved by a blit: geometric edges only, 4x the raster work.
enum class AntiAliasMethod { Fxaa, Msaa4 };

struct RenderSettings {
  int width = 1280;           // frame size; must be even for H.264 video
  int height = 720;
  bool antiAlias = true;      // see antiAliasMethod
  AntiAliasMethod antiAliasMethod = AntiAliasMethod::Fxaa;
  bool shadows = true;        // false: no shadow pass at all
  int shadowMapSize = 2048;   // square depth texture, texels (the maximum when fitted)
  // Fit the shadow map to the casters' size on screen: the smallest power of two (>= 256) whose
  // texels cover at most one pixel where the casters are nearest the camera. A ball filling a
  // third of a 720p frame's height gets 1024, not 2048 (4x fewer depth texels to rasterise).
  bool fitShadowMap = true;
  float shadowSoftness = 1.0f;  // PCF tap spacing in shadow-map texels
  // Smooth silhouettes: dynamic meshes that are not flat-shaded are drawn from PN triangles
  // (refine.h) bound to their vertices, each triangle as 9 or 4 (about 12k triangles per mesh at
  // most; meshes of more than 3000 triangles, fine enough, as they are).
  bool smoothSilhouettes = true;
  // Contact shadows: every dynamic mesh (the first 16) darkens the ambient (and 3/4 of the direct
  // light) of the ground and the other meshes near it (analytic ellipsoid occlusion).
  bool contactShadows = true;
  // Draw the sky and the grounds (without the shadows and contact shadows they receive) once, and
  // copy that background into each frame while the camera, light, sky and grounds stay as they
  // were; FXAA then runs only around what the frame adds (the meshes, the shadows on the
  // grounds) and the rest comes from the background's anti-aliased copy. The image is the same
  // either way (tests/render); off: every pass every frame. No effect with Msaa4.
  bool cacheBackground = true;
  std::string fontPath = kDefaultFontPath;  // overlay font (loaded only if overlay text is set)
  float overlayPixelHeight = 0.0f;  // 0: height / 36, at least 12 px
  // Measure each pass (glFinish after each): fills RenderTimings::passMs. Costs a little speed
  // (the passes no longer overlap inside the driver); for profiling only.
  bool profilePasses = false;
};

// The passes of one frame, in order, for RenderSettings::profilePasses.
// Background: the cached background copied in (or the depth buffer cleared), and the cache
// redrawn when it is out of date.
enum class RenderPass { Upload, Shadow, Background, Opaque, Ground, Sky, Translucent, AntiAlias, Overlay, Count };
const char* passName(RenderPass pass);
inline constexpr std::size_t kRenderPassCount = static_cast<std::size_t>(RenderPass::Count);

struct RenderTimings {
  double renderMs = 0.0;    // last render() (GL work finished: glFinish included; includes the
                            // anti-aliasing pass, FXAA or MSAA resolve)
  double readbackMs = 0.0;  // last readPixels() (glReadPixels, plus the row flip if top-down)
  double totalRenderMs = 0.0;
  double totalReadbackMs = 0.0;
  std::uint64_t frames = 0;
  std::uint64_t readbacks = 0;
  // profilePasses only: total ms per pass over all frames (Upload = dynamic vertex uploads).
  double passMs[kRenderPassCount] = {};
};


using MeshId = std::uint32_t;

class Renderer {
public:
  // Creates the GL context and GL resources. Throws RenderError.
  explicit Renderer(const RenderSettings& settings = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  float aspect() const;

  // --- Meshes. Triangle indices: 3 per triangle, each < vertex count. Throws RenderError on
  // bad sizes or indices. Normals are smooth, area-weighted, recomputed by the renderer.
  // A soft body: topology and material once; positions each frame with updateDynamicMesh.
  // `refine` false: drawn as given, never from a smoother surface (a rigid collider that moves).
  MeshId addDynamicMesh(std::size_t vertexCount, std::span<const std::uint32_t> triangles,
                        const Material& material, bool refine = true);
  // positions: x, y, z per vertex (3 * vertexCount floats). `flat` (empty, or one per vertex):
  // nonzero where a smooth (refined) surface must stay flat, e.g. a vertex resting on a thin
  // collider wall, which a bulging patch would poke through.
  void updateDynamicMesh(MeshId id, std::span<const float> positions, std::span<const std::uint8_t> flat = {});
  // A collider or prop that never moves (see makeBox / makeCylinder / makeSphere).
  MeshId addStaticMesh(std::span<const float> positions, std::span<const std::uint32_t> triangles,
                       const Material& material);
  MeshId addStaticMesh(const MeshData& mesh, const Material& material);
  // A square checkered floor through `point` with the given normal, halfExtent from the point in
  // each direction, tiles of tileSize alternating colourA/colourB. It receives shadows, casts
  // none, fades into the bottom sky colour towards its edge and is left out of the shadow bounds.
  MeshId addGround(glm::vec3 point, glm::vec3 normal, float halfExtent,
                   glm::vec3 colourA = {0.78f, 0.78f, 0.76f},
                   glm::vec3 colourB = {0.58f, 0.60f, 0.62f}, float tileSize = 0.5f);
  // Moves a ground (a plane collider that moves): through `point`, its axes as added turned by
  // `rotation`; its checker moves with it.
  void placeGround(MeshId id, glm::vec3 point, const glm::mat3& rotation);

  // --- Scene.
  void setCamera(const Camera& camera);  // throws RenderError when position == target
  void setLight(const Light& light);
  void setSky(glm::vec3 top, glm::vec3 bottom);  // vertical gradient, top row = top colour
  // (The shadow map covers the bounds of every mesh but the grounds, fitted anew each frame.)
  // Text lines drawn top-left on a translucent dark backing (empty: no overlay). UTF-8.
  void setOverlayText(std::vector<std::string> lines);

  // --- Frames.
  void render();
  // The last rendered frame as RGBA8, rows TOP-DOWN (row 0 = top of the image), alpha 255.
  // BottomUp: GL's own order, one copy less (the video encoder flips for free).
  void readPixels(std::vector<std::uint8_t>& rgba, RowOrder order = RowOrder::TopDown);
  Image readImage();

  const RenderTimings& timings() const;
  // GL_RENDERER / GL_VERSION, for logs.
  std::string glInfo() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace springy::render

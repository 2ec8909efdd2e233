// Rendering tests: orientation, exact sky colour, a lit and shadowed known scene, translucency,
// overlay text, dynamic meshes and the mesh builders. Everything runs on OSMesa (llvmpipe).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/error.h"
#include "render/image.h"
#include "render/look.h"
#include "render/mesh_builders.h"
#include "render/renderer.h"
#include "test_util.h"

using namespace springy::render;
using springy::render::test::dump;
using springy::render::test::luminance;
using springy::render::test::pixel;
using springy::render::test::regionMean;
using springy::render::test::small;

enum class Aa { None, Fxaa, Msaa };
RenderSettings withAa(RenderSettings s, Aa aa) {
  s.antiAlias = aa != Aa::None;
  s.antiAliasMethod = aa == Aa::Msaa ? AntiAliasMethod::Msaa4 : AntiAliasMethod::Fxaa;
  return s;
}
std::string aaName(Aa aa) { return aa == Aa::None ? "NoAA" : aa == Aa::Fxaa ? "FXAA" : "MSAA"; }

class UniformSky : public ::testing::TestWithParam<Aa> {};

// Anti-aliasing must not touch flat areas: every pixel keeps the exact sky colour.
TEST_P(UniformSky, EveryPixelIsTheSkyColour) {
  Renderer r(withAa(small(64, 48), GetParam()));
  const glm::vec3 sky(100.0f / 255.0f, 150.0f / 255.0f, 200.0f / 255.0f);
  r.setSky(sky, sky);
  r.render();
  std::vector<std::uint8_t> rgba;
  r.readPixels(rgba);
  ASSERT_EQ(rgba.size(), 64u * 48u * 4u);
  for (std::size_t i = 0; i < rgba.size(); i += 4) {
    ASSERT_EQ(rgba[i], 100) << "pixel " << i / 4;
    ASSERT_EQ(rgba[i + 1], 150) << "pixel " << i / 4;
    ASSERT_EQ(rgba[i + 2], 200) << "pixel " << i / 4;
    ASSERT_EQ(rgba[i + 3], 255) << "pixel " << i / 4;
  }
}
INSTANTIATE_TEST_SUITE_P(RenderScene, UniformSky, ::testing::Values(Aa::None, Aa::Fxaa, Aa::Msaa),
                         [](const auto& p) { return aaName(p.param); });

TEST(RenderScene, GradientSkyTopRowIsTopColour) {
  Renderer r(small());
  r.setSky({1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f});  // red top, blue bottom
  r.render();
  std::vector<std::uint8_t> rgba;
  r.readPixels(rgba);
  for (int x = 0; x < 64; ++x) {
    const glm::vec3 top = pixel(rgba, 64, x, 0), bottom = pixel(rgba, 64, x, 47);
    EXPECT_GE(top.r, 250.0f);
    EXPECT_LE(top.b, 5.0f);
    EXPECT_GE(bottom.b, 250.0f);
    EXPECT_LE(bottom.r, 5.0f);
  }
  // Monotonic in between.
  for (int y = 1; y < 48; ++y) EXPECT_LE(pixel(rgba, 64, 10, y).r, pixel(rgba, 64, 10, y - 1).r);
}

TEST(RenderScene, ObjectHighInViewLandsInTopHalf) {
  Renderer r(small());
  const glm::vec3 sky(0.5f);
  r.setSky(sky, sky);
  Camera cam;
  cam.position = {0.0f, 0.0f, 5.0f};
  cam.target = {0.0f, 0.0f, 0.0f};
  r.setCamera(cam);
  Material m;
  m.colour = {1.0f, 0.1f, 0.1f};
  r.addStaticMesh(makeBox({0.0f, 1.2f, 0.0f}, glm::vec3(0.3f)), m);
  r.render();
  std::vector<std::uint8_t> rgba;
  r.readPixels(rgba);
  int topCount = 0, bottomCount = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const glm::vec3 p = pixel(rgba, 64, x, y);
      if (p.r > p.g + 40.0f) (y < 24 ? topCount : bottomCount)++;
    }
  EXPECT_GT(topCount, 10);
  EXPECT_EQ(bottomCount, 0);
  // And where the camera maths says it is.
  const glm::vec3 c = projectToPixel(cam, {0.0f, 1.2f, 0.3f}, 64, 48);
  const glm::vec3 p = pixel(rgba, 64, static_cast<int>(c.x), static_cast<int>(c.y));
  EXPECT_GT(p.r, p.g + 40.0f);
}

// A red sphere above a uniformly coloured ground, light from above.
class KnownScene : public ::testing::Test {
protected:
  static constexpr int W = 160, H = 120;
  const glm::vec3 sphereColour{0.85f, 0.2f, 0.15f};
  const glm::vec3 groundColour{0.7f, 0.7f, 0.7f};
  const glm::vec3 sphereCentre{0.0f, 1.0f, 0.0f};
  Light light;
  Camera cam;

  Image renderScene(bool shadows, bool aa, AntiAliasMethod method = AntiAliasMethod::Fxaa,
                    RenderTimings* timings = nullptr) {
    RenderSettings s = small(W, H, aa);
    s.antiAliasMethod = method;
    s.shadows = shadows;
    s.profilePasses = timings != nullptr;
    Renderer r(s);
    light.direction = {-0.2f, -1.0f, -0.1f};
    light.colour = glm::vec3(1.0f);
    light.ambient = glm::vec3(0.2f);
    r.setLight(light);
    cam.position = {0.0f, 2.5f, 5.0f};
    cam.target = {0.0f, 0.5f, 0.0f};
    r.setCamera(cam);
    r.addGround({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 60.0f, groundColour, groundColour);
    Material m;
    m.colour = sphereColour;
    m.specular = 0.0f;
    r.addStaticMesh(makeSphere(sphereCentre, 0.5f, 24, 48), m);
    r.render();
    if (timings) *timings = r.timings();
    return r.readImage();
  }

  // Where the sphere centre's shadow falls on the ground (y = 0).
  glm::vec3 shadowPoint() const {
    const glm::vec3 d = glm::normalize(light.direction);
    return sphereCentre + d * (sphereCentre.y / -d.y);
  }
  // Expected display value of lit ground (see the mesh shader): in linear light,
  // colour * (ambient from above + n.l), the ambient from above being 0.2 tinted by the default
  // sky's top colour (luminance 1, mixed 35% into white: docs/look.md); then sRGB-encoded (no
  // tone curve below 0.9).
  glm::vec3 expectedLitGround() const {
    const float ndl = glm::dot(glm::vec3(0, 1, 0), -glm::normalize(light.direction));
    const glm::vec3 sky = srgbToLinear({0.36f, 0.56f, 0.84f});
    const glm::vec3 tint = glm::mix(glm::vec3(1.0f), sky / glm::dot(sky, glm::vec3(0.2126f, 0.7152f, 0.0722f)), 0.35f);
    const glm::vec3 lit = srgbToLinear(groundColour) * (0.2f * tint + ndl);
    glm::vec3 out;
    for (int k = 0; k < 3; ++k) {
      const float c = std::clamp(lit[k], 0.0f, 1.0f);
      out[k] = 255.0f * (c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f);
    }
    return out;
  }
};

TEST_F(KnownScene, BodyColourShadowAndGroundLevel) {
  const Image img = renderScene(true, true);  // FXAA
  dump(img, "known_scene.png");
  // The sphere centre projects onto the sphere: its colour, scaled by lighting (hue preserved).
  const glm::vec3 c = projectToPixel(cam, sphereCentre, W, H);
  const glm::vec3 body = regionMean(img.rgba, W, H, static_cast<int>(c.x), static_cast<int>(c.y), 1);
  ASSERT_GT(glm::length(body), 30.0f);
  const glm::vec3 hue = body / glm::length(body), want = sphereColour / glm::length(sphereColour);
  EXPECT_NEAR(hue.r, want.r, 0.05f);
  EXPECT_NEAR(hue.g, want.g, 0.05f);
  EXPECT_NEAR(hue.b, want.b, 0.05f);

  // Ground in the sphere's shadow is darker than ground far from it.
  const glm::vec3 s = projectToPixel(cam, shadowPoint(), W, H);
  const glm::vec3 far = projectToPixel(cam, {1.6f, 0.0f, 1.0f}, W, H);
  ASSERT_TRUE(s.x >= 0 && s.x < W && s.y >= 0 && s.y < H);
  ASSERT_TRUE(far.x >= 0 && far.x < W && far.y >= 0 && far.y < H);
  const glm::vec3 shadowed = regionMean(img.rgba, W, H, static_cast<int>(s.x), static_cast<int>(s.y), 1);
  const glm::vec3 lit = regionMean(img.rgba, W, H, static_cast<int>(far.x), static_cast<int>(far.y), 2);
  EXPECT_LT(luminance(shadowed), 0.75f * luminance(lit));
  // Lit ground matches the lighting model.
  const glm::vec3 want2 = expectedLitGround();
  EXPECT_NEAR(lit.r, want2.r, 6.0f);
  EXPECT_NEAR(lit.g, want2.g, 6.0f);
  EXPECT_NEAR(lit.b, want2.b, 6.0f);
}

TEST_F(KnownScene, NoShadowsWhenDisabled) {
  const Image img = renderScene(false, false);
  const glm::vec3 s = projectToPixel(cam, shadowPoint(), W, H);
  const glm::vec3 shadowed = regionMean(img.rgba, W, H, static_cast<int>(s.x), static_cast<int>(s.y), 1);
  const glm::vec3 want = expectedLitGround();
  EXPECT_NEAR(luminance(shadowed), luminance(want), 6.0f);
}

TEST_F(KnownScene, NoShadowPassWhenDisabled) {
  RenderTimings on, off;
  renderScene(true, false, AntiAliasMethod::Fxaa, &on);
  renderScene(false, false, AntiAliasMethod::Fxaa, &off);
  const auto shadow = static_cast<std::size_t>(RenderPass::Shadow);
  EXPECT_GT(on.passMs[shadow], 0.0);
  EXPECT_EQ(off.passMs[shadow], 0.0);
}

class KnownSceneAa : public KnownScene, public ::testing::WithParamInterface<AntiAliasMethod> {};

TEST_P(KnownSceneAa, AntiAliasingSoftensEdges) {
  // Count pixels that are neither sphere-like nor ground-like along the silhouette: anti-aliasing
  // adds intermediate colours, so more distinct values appear.
  auto distinct = [](const Image& img) {
    std::vector<bool> seen(1 << 15, false);
    int n = 0;
    for (std::size_t i = 0; i < img.rgba.size(); i += 4) {
      const int key = (img.rgba[i] >> 3) << 10 | (img.rgba[i + 1] >> 3) << 5 | (img.rgba[i + 2] >> 3);
      if (!seen[static_cast<std::size_t>(key)]) seen[static_cast<std::size_t>(key)] = true, ++n;
    }
    return n;
  };
  const Image aa = renderScene(true, true, GetParam()), plain = renderScene(true, false);
  dump(aa, "known_scene_aa.png");
  EXPECT_GT(distinct(aa), distinct(plain));
}

// Along the sphere's left and right silhouette (against the ground) a row of the plain frame
// steps from ground to sphere between two neighbouring pixels. With anti-aliasing, one of those
// two pixels takes a colour in between: its red-minus-green ("sphere-ness") lies well inside
// the step.
TEST_P(KnownSceneAa, EdgePixelsGetIntermediateColours) {
  const Image aa = renderScene(false, true, GetParam()), plain = renderScene(false, false);
  dump(aa, "edges_aa.png");
  auto sphereness = [&](const Image& img, int x, int y) {
    const glm::vec3 p = pixel(img.rgba, W, x, y);
    return p.r - p.g;  // ground: ~0 (grey), sphere: large
  };
  const int cy = static_cast<int>(projectToPixel(cam, sphereCentre, W, H).y);
  int crossings = 0, blended = 0;
  for (int y = cy - 8; y <= cy + 8; ++y)
    for (int x = 0; x + 1 < W; ++x) {
      const float a = sphereness(plain, x, y), b = sphereness(plain, x + 1, y);
      if (std::abs(a - b) < 60.0f) continue;  // not a silhouette step
      ++crossings;
      const float lo = std::min(a, b), hi = std::max(a, b), margin = 0.15f * (hi - lo);
      for (int k : {x, x + 1}) {
        const float v = sphereness(aa, k, y);
        if (v > lo + margin && v < hi - margin) {
          ++blended;
          break;
        }
      }
    }
  EXPECT_GE(crossings, 30);  // 17 rows, 2 sides
  EXPECT_GE(blended, crossings * 6 / 10) << blended << " of " << crossings << " steps blended";
}

INSTANTIATE_TEST_SUITE_P(RenderScene, KnownSceneAa,
                         ::testing::Values(AntiAliasMethod::Fxaa, AntiAliasMethod::Msaa4),
                         [](const auto& p) { return p.param == AntiAliasMethod::Fxaa ? "FXAA" : "MSAA"; });

TEST(RenderScene, TranslucentBodyShowsWhatIsBehind) {
  RenderSettings s = small(96, 64);
  Camera cam;
  cam.position = {0.0f, 0.0f, 6.0f};
  cam.target = {0.0f, 0.0f, 0.0f};
  auto renderWith = [&](float alpha) {
    Renderer r(s);
    r.setCamera(cam);
    Material back;
    back.colour = {0.1f, 0.9f, 0.1f};
    r.addStaticMesh(makeBox({0.0f, 0.0f, -2.0f}, {3.0f, 3.0f, 0.1f}), back);  // green wall
    Material jelly;
    jelly.colour = {0.9f, 0.1f, 0.9f};
    jelly.alpha = alpha;
    r.addStaticMesh(makeSphere({0.0f, 0.0f, 0.0f}, 1.0f), jelly);
    r.render();
    return r.readImage();
  };
  const Image opaque = renderWith(1.0f), jelly = renderWith(0.7f);
  dump(opaque, "opaque.png");
  dump(jelly, "jelly.png");
  const glm::vec3 a = pixel(opaque.rgba, 96, 48, 32), b = pixel(jelly.rgba, 96, 48, 32);
  EXPECT_LT(a.g, 60.0f);
  EXPECT_GT(b.g, a.g + 15.0f);  // green wall shows through
  EXPECT_GT(b.r, 60.0f);        // still mostly the jelly
}

TEST(RenderScene, DynamicMeshFollowsPositions) {
  Renderer r(small(64, 48));
  Camera cam;
  cam.position = {0.0f, 0.0f, 5.0f};
  cam.target = {0.0f, 0.0f, 0.0f};
  r.setCamera(cam);
  r.setSky(glm::vec3(0.0f), glm::vec3(0.0f));
  const MeshData box = makeBox({0.0f, 0.0f, 0.0f}, glm::vec3(0.3f));
  Material m;
  m.colour = {1.0f, 1.0f, 1.0f};
  const MeshId id = r.addDynamicMesh(box.vertexCount(), box.indices, m);
  auto brightCentroidX = [&](float dx) {
    std::vector<float> pos = box.positions;
    for (std::size_t i = 0; i < pos.size(); i += 3) pos[i] += dx;
    r.updateDynamicMesh(id, pos);
    r.render();
    std::vector<std::uint8_t> rgba;
    r.readPixels(rgba);
    double sx = 0;
    int n = 0;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 64; ++x)
        if (pixel(rgba, 64, x, y).r > 20.0f) sx += x, ++n;
    return n ? sx / n : -1.0;
  };
  const double left = brightCentroidX(-1.0f), right = brightCentroidX(1.0f);
  ASSERT_GT(left, 0.0);
  EXPECT_GT(right - left, 15.0);
  EXPECT_THROW(r.updateDynamicMesh(id, std::vector<float>(5, 0.0f)), RenderError);
  EXPECT_EQ(r.timings().frames, 2u);
  EXPECT_GT(r.timings().renderMs, 0.0);
}

// The cached background (RenderSettings::cacheBackground) changes no pixel: a ball moving over a
// checkered ground, beside a static box and a translucent jelly, drawn frame by frame with the
// cache and without, then after the camera, the light and the sky change in turn (each must
// redraw the cache). With FXAA (run only around what a frame draws over the background: a
// checker edge a few pixels from the ball blends with taps reaching into it), without, and with
// MSAA (no cache).
class CachedBackground : public ::testing::TestWithParam<Aa> {};

// The frames of one of two scenes: `topDown` a slab moving over a checker seen from straight above
// (its edges and the checker's lines run along the screen's rows and columns: where a checker line
// meets the slab, FXAA just outside the slab's rectangle blends taps from inside it); otherwise a
// box moving in perspective beside a static box and a translucent jelly, while the camera, the
// light and the sky change in turn (each must redraw the cache).
std::vector<std::vector<std::uint8_t>> cachedBackgroundFrames(Aa aa, bool cache, bool topDown) {
  RenderSettings s = withAa(small(240, 136), aa);
  s.cacheBackground = cache;
  Renderer r(s);
  Camera cam;
  cam.position = topDown ? glm::vec3(0.0f, 5.0f, 0.0f) : glm::vec3(0.0f, 2.0f, 7.0f);
  cam.target = topDown ? glm::vec3(0.0f) : glm::vec3(0.0f, 0.5f, 0.0f);
  r.setCamera(cam);
  Light slanted;
  slanted.direction = {-1.0f, -0.8f, 0.2f};  // shadows fall beside the bodies
  r.setLight(slanted);
  r.addGround({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 20.0f, {0.8f, 0.8f, 0.75f}, {0.3f, 0.35f, 0.4f},
              topDown ? 0.5f : 0.15f);
  if (!topDown) {
    Material box;
    box.colour = {0.4f, 0.6f, 0.9f};
    r.addStaticMesh(makeBox({2.0f, 0.3f, -1.0f}, {1.5f, 0.3f, 1.0f}), box);
    Material jelly;
    jelly.colour = {0.9f, 0.2f, 0.6f};
    jelly.alpha = 0.6f;
    r.addStaticMesh(makeSphere({-2.0f, 0.6f, 0.5f}, 0.6f), jelly);
  }
  const MeshData body = makeBox({0.0f, 0.0f, 0.0f}, topDown ? glm::vec3(0.6f, 0.05f, 0.45f) : glm::vec3(0.5f));
  Material red;
  red.colour = {0.85f, 0.2f, 0.15f};
  red.flat = true;
  const MeshId id = r.addDynamicMesh(body.vertexCount(), body.indices, red);
  std::vector<std::vector<std::uint8_t>> out;
  for (int f = 0; f < 12; ++f) {
    if (!topDown && f == 3) {
      cam.position = {1.0f, 3.0f, 6.0f};
      r.setCamera(cam);
    } else if (!topDown && f == 4) {
      Light light;
      light.direction = {0.3f, -1.0f, -0.2f};
      r.setLight(light);
    } else if (!topDown && f == 5) {
      r.setSky({0.36f, 0.56f, 0.84f}, {0.9f, 0.8f, 0.7f});  // the default top: only the bottom changes
    }
    std::vector<float> pos = body.positions;
    const float x = -2.5f + 0.45f * static_cast<float>(f), y = topDown ? 0.5f : f % 2 ? 0.45f : 1.5f;
    const float z = topDown ? 0.13f * static_cast<float>(f % 5) - 0.3f : 0.0f;
    for (std::size_t i = 0; i < pos.size(); i += 3) pos[i] += x, pos[i + 1] += y, pos[i + 2] += z;
    r.updateDynamicMesh(id, pos);
    r.setOverlayText({"frame " + std::string(static_cast<std::size_t>(f % 3 + 1), 'W')});  // as wide as it says
    r.render();
    out.emplace_back();
    r.readPixels(out.back());
  }
  return out;
}

TEST_P(CachedBackground, GivesTheSameImageAsDrawingEverything) {
  for (bool topDown : {false, true}) {
    const auto cached = cachedBackgroundFrames(GetParam(), true, topDown);
    const auto drawn = cachedBackgroundFrames(GetParam(), false, topDown);
    for (std::size_t f = 0; f < cached.size(); ++f) {
      std::size_t differ = 0;
      for (std::size_t i = 0; i < cached[f].size(); ++i) differ += cached[f][i] != drawn[f][i];
      EXPECT_EQ(differ, 0u) << (topDown ? "top down" : "perspective") << ", frame " << f;
      if (f > 0) {
        EXPECT_NE(cached[f], cached[f - 1]) << "frame " << f << " shows nothing new";
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(RenderScene, CachedBackground, ::testing::Values(Aa::None, Aa::Fxaa, Aa::Msaa),
                         [](const ::testing::TestParamInfo<Aa>& i) { return aaName(i.param); });

TEST(RenderScene, OverlayTextDrawsTopLeft) {
  RenderSettings s = small(256, 128);
  const glm::vec3 sky(0.5f);
  auto frame = [&](bool text) {
    Renderer r(s);
    r.setSky(sky, sky);
    if (text) r.setOverlayText({"jelly drop", "t = 1.50 s", "implicit Euler, dt = 1 ms"});
    r.render();
    return r.readImage();
  };
  const Image plain = frame(false), text = frame(true);
  dump(text, "overlay.png");
  int changedTopLeft = 0, changedBottomRight = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 256; ++x) {
      const bool diff = pixel(plain.rgba, 256, x, y) != pixel(text.rgba, 256, x, y);
      if (x < 128 && y < 64) changedTopLeft += diff;
      if (x >= 200 && y >= 100) changedBottomRight += diff;
    }
  EXPECT_GT(changedTopLeft, 500);
  EXPECT_EQ(changedBottomRight, 0);
  // White glyph pixels exist (text brighter than the grey sky).
  int white = 0;
  for (std::size_t i = 0; i < text.rgba.size(); i += 4) white += text.rgba[i] > 230;
  EXPECT_GT(white, 20);
}

TEST(RenderScene, BadFontPathThrowsNamingPath) {
  RenderSettings s = small();
  s.fontPath = "/nonexistent/font.ttf";
  Renderer r(s);
  r.setOverlayText({"x"});
  try {
    r.render();
    FAIL() << "expected RenderError";
  } catch (const RenderError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/font.ttf"), std::string::npos);
  }
}

TEST(RenderScene, FrameBoundsShowsTheWholeBox) {
  const glm::vec3 lo(-2.0f, 0.0f, -1.0f), hi(3.0f, 4.0f, 1.5f);
  const Camera cam = frameBounds(lo, hi, 16.0f / 9.0f);
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 corner((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
    const glm::vec3 p = projectToPixel(cam, corner, 1280, 720);
    EXPECT_GE(p.x, 0.0f);
    EXPECT_LE(p.x, 1280.0f);
    EXPECT_GE(p.y, 0.0f);
    EXPECT_LE(p.y, 720.0f);
    EXPECT_LT(p.z, 1.0f);
  }
}

// Looking straight down (or up) the view is parallel to up: lookAt built a degenerate basis and
// the frame was only sky. Another up vector is chosen: the target is at the centre, -Z at the top
// when looking down (as a camera tilted down from a level view along -Z), +Z when looking up.
TEST(RenderScene, CameraStraightAboveOrBelowItsTarget) {
  Camera down;
  down.position = {0.0f, 30.0f, 0.0f};
  down.target = {0.0f, 0.0f, 0.0f};
  const glm::mat4 view = down.view();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_TRUE(std::isfinite(view[c][r]));
  glm::vec3 p = projectToPixel(down, {0.0f, 0.0f, 0.0f}, 64, 48);
  EXPECT_NEAR(p.x, 32.0f, 1e-3f);
  EXPECT_NEAR(p.y, 24.0f, 1e-3f);
  EXPECT_LT(projectToPixel(down, {0.0f, 0.0f, -1.0f}, 64, 48).y, 24.0f);  // -Z towards the top
  Camera up = down;
  up.position = {0.0f, -30.0f, 0.0f};
  EXPECT_LT(projectToPixel(up, {0.0f, 0.0f, 1.0f}, 64, 48).y, 24.0f);  // +Z towards the top
  // Nearly straight down: the same picture as straight down, not a spin by the tiny offset.
  Camera nearly = down;
  nearly.position.x = 1e-5f;
  p = projectToPixel(nearly, {0.0f, 0.0f, -1.0f}, 64, 48);
  EXPECT_NEAR(p.x, 32.0f, 0.1f);
  EXPECT_LT(p.y, 24.0f);

  // And it renders: a red box under the camera fills the centre, no sky there.
  Renderer r(small());
  const glm::vec3 sky(0.5f);
  r.setSky(sky, sky);
  r.setCamera(down);
  Material m;
  m.colour = {1.0f, 0.1f, 0.1f};
  r.addStaticMesh(makeBox({0.0f, 0.0f, 0.0f}, glm::vec3(3.0f)), m);
  r.render();
  std::vector<std::uint8_t> rgba;
  r.readPixels(rgba);
  const glm::vec3 centre = pixel(rgba, 64, 32, 24);
  EXPECT_GT(centre.r, centre.g + 40.0f);
}

TEST(RenderScene, CameraAtItsTargetThrows) {
  Camera c;
  c.position = c.target = {1.0f, 2.0f, 3.0f};
  EXPECT_THROW(c.view(), RenderError);
  Renderer r(small());
  EXPECT_THROW(r.setCamera(c), RenderError);
}

TEST(RenderScene, InvalidInputsThrow) {
  Renderer r(small());
  const std::vector<float> pos{0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<std::uint32_t> bad{0, 1, 3};
  EXPECT_THROW(r.addStaticMesh(pos, bad, Material{}), RenderError);
  EXPECT_THROW(r.addDynamicMesh(3, std::vector<std::uint32_t>{0, 1}, Material{}), RenderError);
  EXPECT_THROW(r.updateDynamicMesh(99, pos), RenderError);
  EXPECT_THROW(Renderer(small(0, 10)), RenderError);
}

// Every builder makes closed meshes wound counter-clockwise seen from outside.
TEST(MeshBuilders, OutwardWinding) {
  const glm::vec3 c(0.5f, 1.0f, -0.5f);
  for (const MeshData& m : {makeBox(c, {0.5f, 0.2f, 0.3f}), makeSphere(c, 0.7f),
                            makeCylinder(c - glm::vec3(0.1f, 0.5f, 0), c + glm::vec3(0.1f, 0.5f, 0), 0.1f)}) {
    ASSERT_EQ(m.indices.size() % 3, 0u);
    ASSERT_GT(m.indices.size(), 0u);
    double signedVolume = 0.0;
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
      auto P = [&](std::uint32_t i) {
        return glm::dvec3(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]) -
               glm::dvec3(c);
      };
      const glm::dvec3 a = P(m.indices[t]), b = P(m.indices[t + 1]), d = P(m.indices[t + 2]);
      const double v = glm::dot(a, glm::cross(b, d));
      EXPECT_GE(v, -1e-9) << "triangle " << t / 3 << " winds inward";
      signedVolume += v / 6.0;
    }
    EXPECT_GT(signedVolume, 0.0);
  }
  const MeshData box = makeBox(c, glm::vec3(1.0f));
  EXPECT_EQ(box.vertexCount(), 24u);
  EXPECT_EQ(box.indices.size(), 36u);
}

// A cube of 8 shared vertices: smooth normals shade each face as a gradient (the corners'
// normals point diagonally); flat shading gives each face one uniform colour.
TEST(RenderScene, FlatShadingMakesEachFaceUniform) {
  RenderSettings s = small(96, 96);
  s.shadows = false;
  Camera cam;
  cam.position = {0.0f, 0.0f, 4.0f};
  cam.target = {0.0f, 0.0f, 0.0f};
  cam.fovYDeg = 40.0f;
  const std::vector<float> corners = {-1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1,
                                      -1, -1, 1,  1, -1, 1,  1, 1, 1,  -1, 1, 1};
  const std::vector<std::uint32_t> tris = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                           2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
  Material m;
  m.colour = {0.8f, 0.8f, 0.8f};
  m.specular = 0.0f;
  // The front face (z = +1) fills the middle of the view; compare two points on it.
  auto spread = [&](bool flat) {
    m.flat = flat;
    Renderer fresh(s);
    fresh.setCamera(cam);
    fresh.setSky(glm::vec3(0.0f), glm::vec3(0.0f));
    const MeshId id = fresh.addDynamicMesh(8, tris, m);
    fresh.updateDynamicMesh(id, corners);
    fresh.render();
    std::vector<std::uint8_t> rgba;
    fresh.readPixels(rgba);
    const glm::vec3 a = regionMean(rgba, 96, 96, 36, 36, 1), b = regionMean(rgba, 96, 96, 60, 60, 1);
    EXPECT_GT(luminance(a), 10.0f);  // lit, not sky
    return std::fabs(luminance(a) - luminance(b));
  };
  EXPECT_LT(spread(true), 1.0f);
  EXPECT_GT(spread(false), 3.0f);
}

// The look of a frame (issue 17): the tone curve as the GPU runs it, contact shadows, and a
// translucent body showing only its nearest surface. Small frames, no anti-aliasing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <vector>

#include "render/camera.h"
#include "render/image.h"
#include "render/look.h"
#include "render/mesh_builders.h"
#include "render/refine.h"
#include "render/renderer.h"
#include "test_util.h"

using namespace springy::render;
using springy::render::test::dump;
using springy::render::test::luminance;
using springy::render::test::pixel;
using springy::render::test::regionMean;
using springy::render::test::small;

// Per channel, a brighter linear input never gives a darker display value, from black to 16x
// over white; the curve reaches white and stays below it before (no hard clip at 1.0).
TEST(Look, ToneCurveIsMonotonic) {
  std::vector<glm::vec3> in;
  for (int i = 0; i < 2048; ++i) {
    const float x = 16.0f * std::pow(static_cast<float>(i) / 2047.0f, 3.0f);  // dense near black
    in.push_back({x, 0.5f * x, 0.25f * x});
  }
  const std::vector<glm::u8vec3> out = toneCurveOnGpu(in);
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 1; i < out.size(); ++i)
    for (int k = 0; k < 3; ++k) ASSERT_GE(out[i][k], out[i - 1][k]) << "input " << in[i][k] << " channel " << k;
  EXPECT_EQ(out.front(), glm::u8vec3(0));
  EXPECT_EQ(out.back().r, 255);
  // A saturated highlight keeps its hue: red at 2.0 with green and blue at 0.5 (linear) does
  // not clip to (255, 188, 188) per channel; it is compressed as a whole and turns towards
  // white, green well below 188.
  const std::vector<glm::u8vec3> hot = toneCurveOnGpu(std::vector<glm::vec3>{{2.0f, 0.5f, 0.5f}});
  EXPECT_GE(hot[0].r, 250);
  EXPECT_LT(hot[0].g, 175);
  EXPECT_GT(hot[0].g, 130);
}

// The documented sky colours (scenes/README.md: sky_top, sky_bottom defaults) and the
// renderer's own come out of the curve as they went in, within 1/255.
TEST(Look, ToneCurveKeepsTheSkyColours) {
  const std::vector<glm::vec3> sky = {
      {0.36f, 0.56f, 0.82f}, {0.85f, 0.9f, 0.95f}, {0.36f, 0.56f, 0.84f}, {0.86f, 0.90f, 0.95f}, {0.5f, 0.5f, 0.5f}};
  std::vector<glm::vec3> linear;
  for (const glm::vec3& c : sky) linear.push_back(srgbToLinear(c));
  const std::vector<glm::u8vec3> out = toneCurveOnGpu(linear);
  for (std::size_t i = 0; i < sky.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(out[i][k], sky[i][k] * 255.0f, 1.0f) << "colour " << i << " channel " << k;
}

// A ball resting on the ground, no shadow map (so only the contact shadow can darken the
// ground), seen from above at an angle.
class ContactShadow : public ::testing::Test {
 protected:
  static constexpr int W = 128, H = 96;
  static constexpr float R = 0.5f;
  Camera cam;
  Image render(bool contact, bool shadows = false, glm::vec3 lightDirection = {0.0f, -1.0f, 0.0f}) {
    RenderSettings s = small(W, H);
    s.shadows = shadows;
    s.contactShadows = contact;
    Renderer r(s);
    cam.position = {0.0f, 6.0f, 2.0f};
    cam.target = {0.0f, 0.0f, 0.0f};
    cam.fovYDeg = 70.0f;
    r.setCamera(cam);
    Light light;
    light.direction = lightDirection;
    r.setLight(light);
    const glm::vec3 grey(0.6f);
    r.addGround({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 40.0f, grey, grey);
    const MeshData ball = makeSphere({0.0f, R, 0.0f}, R, 12, 24);
    Material m;
    m.colour = {0.2f, 0.4f, 0.8f};
    const MeshId id = r.addDynamicMesh(ball.vertexCount(), ball.indices, m);
    r.updateDynamicMesh(id, ball.positions);
    r.render();
    return r.readImage();
  }
  glm::vec3 at(const Image& img, glm::vec3 world, int radius = 1) {
    const glm::vec3 p = projectToPixel(cam, world, W, H);
    EXPECT_TRUE(p.x >= 0 && p.x < W && p.y >= 0 && p.y < H);
    return regionMean(img.rgba, W, H, static_cast<int>(p.x), static_cast<int>(p.y), radius);
  }
};

TEST_F(ContactShadow, DarkensTheGroundAtTheBaseAndNotThreeSizesAway) {
  const Image on = render(true), off = render(false);
  dump(on, "contact_on.png");
  dump(off, "contact_off.png");
  // Just in front of the ball's foot (0.2 R beyond its outline, towards the camera).
  const glm::vec3 foot{0.0f, 0.0f, 1.2f * R};
  EXPECT_LT(luminance(at(on, foot)), 0.9f * luminance(at(off, foot)));
  // Beside it, to the left and right.
  for (float x : {-1.3f * R, 1.3f * R})
    EXPECT_LT(luminance(at(on, {x, 0.0f, 0.0f})), 0.92f * luminance(at(off, {x, 0.0f, 0.0f})));
  // Three body sizes (6 R) from the centre, in four directions: untouched.
  for (const glm::vec3 far :
       {glm::vec3(6 * R, 0, 0), glm::vec3(-6 * R, 0, 0), glm::vec3(0, 0, 6 * R), glm::vec3(0, 0, -6 * R)}) {
    const glm::vec3 a = at(on, far, 0), b = at(off, far, 0);
    EXPECT_EQ(a, b) << "at " << far.x << ", " << far.z;
  }
}

// With the shadow map on and the light from the side, the contact shadow still darkens the
// ground all round the ball's base (renderer.cpp groundPass draws the contact shadows over the
// bodies' reach and the shadow taps only over the map's footprint; at this size the probes lie
// in both, and tests/render/same_frames.sh checked the rest of the reach on every scene).
TEST_F(ContactShadow, DarkensAllRoundTheBaseBesideTheShadowMapsFootprint) {
  const glm::vec3 fromTheRight{-1.0f, -0.8f, 0.0f};
  const Image on = render(true, true, fromTheRight), off = render(false, true, fromTheRight);
  dump(on, "contact_shadowed_on.png");
  // Left, right and in front (behind, the ball hides the ground from this camera).
  for (const glm::vec3 p : {glm::vec3(1.4f * R, 0, 0), glm::vec3(-1.4f * R, 0, 0), glm::vec3(0, 0, 1.4f * R)})
    EXPECT_LT(luminance(at(on, p)), 0.95f * luminance(at(off, p))) << "at " << p.x << ", " << p.z;
}

// A translucent jelly-like block seen from above at an angle, its bottom hidden behind its top
// and sides. Two versions differ only in the bottom: flat, or a fan whose centre is pushed up
// into the body (the creases of a star). Within the block's outline the frames must be the same
// pixel for pixel: no edge of the far-side triangles shows through.
namespace {
MeshData block(bool starBottom) {
  // Top and sides from makeCylinder (own vertices per cap); the bottom replaced.
  const int seg = 24;
  const float r = 1.0f, h = 1.0f;
  MeshData m = makeCylinder({0.0f, 0.0f, 0.0f}, {0.0f, h, 0.0f}, r, seg);
  // Drop makeCylinder's bottom cap: keep the triangles with no vertex below y = 0.5 h whose
  // normal points down (the cap); simpler: rebuild from the top cap and sides by filtering.
  MeshData kept;
  kept.positions = m.positions;
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    bool allBottom = true;
    for (int k = 0; k < 3; ++k) allBottom &= m.positions[3 * m.indices[t + k] + 1] < 0.01f;
    if (!allBottom)
      kept.indices.insert(kept.indices.end(), m.indices.begin() + static_cast<long>(t),
                          m.indices.begin() + static_cast<long>(t) + 3);
  }
  // The new bottom: its own ring of vertices and a centre.
  const std::uint32_t first = static_cast<std::uint32_t>(kept.positions.size() / 3);
  for (int i = 0; i < seg; ++i) {
    const float a = 6.2831853f * static_cast<float>(i) / seg;
    kept.positions.insert(kept.positions.end(), {r * std::cos(a), 0.0f, -r * std::sin(a)});
  }
  kept.positions.insert(kept.positions.end(), {0.0f, starBottom ? 0.6f * h : 0.0f, 0.0f});
  const std::uint32_t centre = first + seg;
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(seg); ++i) {
    const std::uint32_t a = first + i, b = first + (i + 1) % seg;
    kept.indices.insert(kept.indices.end(), {centre, b, a});  // facing down (outside)
  }
  return kept;
}
}  // namespace

TEST(Look, TranslucentBodyShowsNoFarSideEdges) {
  Camera cam;
  cam.position = {0.0f, 3.2f, 3.2f};
  cam.target = {0.0f, 0.4f, 0.0f};
  cam.fovYDeg = 45.0f;
  const int W = 96, H = 72;
  auto renderWith = [&](const MeshData& mesh, float alpha) {
    RenderSettings s = small(W, H);
    s.shadows = false;
    Renderer r(s);
    r.setCamera(cam);
    r.addGround({0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 20.0f, glm::vec3(0.75f), glm::vec3(0.45f), 0.25f);
    Material jelly;
    jelly.colour = {0.95f, 0.2f, 0.45f};
    jelly.alpha = alpha;
    jelly.shininess = 64.0f;
    r.addStaticMesh(mesh, jelly);
    r.render();
    return r.readImage();
  };
  const Image flat = renderWith(block(false), 0.7f), star = renderWith(block(true), 0.7f);
  // The block's outline: where an opaque block differs from the empty scene.
  const Image opaque = renderWith(block(false), 1.0f);
  const Image empty = renderWith(MeshData{}, 1.0f);
  dump(flat, "jelly_flat_bottom.png");
  dump(star, "jelly_star_bottom.png");
  int inside = 0, differ = 0, maxDiff = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (glm::length(pixel(opaque.rgba, W, x, y) - pixel(empty.rgba, W, x, y)) < 1.0f) continue;
      ++inside;
      const glm::vec3 d = glm::abs(pixel(flat.rgba, W, x, y) - pixel(star.rgba, W, x, y));
      const int m = static_cast<int>(std::max({d.r, d.g, d.b}));
      maxDiff = std::max(maxDiff, m);
      if (m > 0) ++differ;
    }
  EXPECT_GT(inside, W * H / 6);  // the block covers a good part of the frame
  EXPECT_EQ(differ, 0) << "max difference " << maxDiff;
  // And it is translucent: the ground's checker shows through (the frame is not the opaque one).
  int seeThrough = 0;
  for (std::size_t i = 0; i < flat.rgba.size(); i += 4) seeThrough += flat.rgba[i + 1] != opaque.rgba[i + 1];
  EXPECT_GT(seeThrough, inside / 2);
}

// Smooth silhouettes: PN triangles over an octahedron (6 vertices on the unit sphere, normals
// pointing out) make a closed surface through its vertices that is far rounder than its flat
// faces: no refined vertex is off the sphere by more than 0.6 of the flat faces' worst (a face's
// centre is 0.42 inside it; a flat midpoint of an edge 0.29). An octahedron is PN triangles'
// hardest case (90 degrees between neighbouring normals): its face centres stay 0.23 inside.
TEST(Look, PnTrianglesRoundACoarseMeshWithoutCracks) {
  const std::vector<glm::vec3> p = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const std::vector<std::uint32_t> tris = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  for (int level : {2, 3}) {
    const PnRefinement pn(tris, p.size(), level);
    ASSERT_TRUE(pn.active());
    EXPECT_EQ(pn.triangles().size(), tris.size() * static_cast<std::size_t>(level * level));
    std::vector<glm::vec3> out;
    pn.evaluate(p, p, out);  // on the unit sphere the normals are the positions
    ASSERT_EQ(out.size(), pn.vertexCount());
    for (std::size_t i = 0; i < p.size(); ++i) EXPECT_EQ(out[i], p[i]);  // through the vertices
    float worst = 0.0f;
    for (const glm::vec3& q : out) worst = std::max(worst, std::fabs(glm::length(q) - 1.0f));
    const float flatWorst = 1.0f - glm::length(glm::vec3(1.0f) / 3.0f);
    EXPECT_LT(worst, 0.6f * flatWorst) << "level " << level;
    // Closed: every directed edge of the refined mesh once, and its reverse once.
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    const std::vector<std::uint32_t>& t = pn.triangles();
    for (std::size_t i = 0; i < t.size(); i += 3)
      for (int k = 0; k < 3; ++k) ++directed[{t[i + k], t[i + (k + 1) % 3]}];
    for (const auto& [e, n] : directed) {
      EXPECT_EQ(n, 1);
      EXPECT_EQ(directed.count({e.second, e.first}), 1u);
    }
  }
}

// A vertex resting on a collider keeps the drawn surface flat (updateDynamicMesh's `flat`): with
// every vertex flat, the refined octahedron is the flat one subdivided, each refined vertex on
// its coarse face's plane (none bulges out, through a wall a face lies on); with one vertex flat,
// the refined points near it move in (never further out than the round surface's).
TEST(Look, PnTrianglesStayFlatAtRestingVertices) {
  const std::vector<glm::vec3> p = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const std::vector<std::uint32_t> tris = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  const PnRefinement pn(tris, p.size(), 3);
  std::vector<glm::vec3> out;
  pn.evaluate(p, p, out, std::vector<std::uint8_t>(p.size(), 1));
  // The octahedron's faces are the planes |x| + |y| + |z| = 1 of their octants.
  for (const glm::vec3& q : out) EXPECT_NEAR(std::fabs(q.x) + std::fabs(q.y) + std::fabs(q.z), 1.0f, 1e-6f);
  // Only vertex 0 (+x) flat.
  std::vector<std::uint8_t> flat(p.size(), 0);
  flat[0] = 1;
  std::vector<glm::vec3> round, one;
  pn.evaluate(p, p, round);
  pn.evaluate(p, p, one, flat);
  int onChord = 0;
  for (std::size_t i = p.size(); i < one.size(); ++i) {
    if (one[i] == round[i]) continue;  // away from vertex 0
    EXPECT_LT(glm::length(one[i]), glm::length(round[i]) + 1e-6f) << i;  // flatter, never further out
    ++onChord;
  }
  EXPECT_GT(onChord, 0);
}

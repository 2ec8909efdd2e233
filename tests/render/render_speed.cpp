// Not a test: renders a representative 1280x720 scene (ground, gallows, a deforming ~5k-triangle
// jelly, overlay) and prints per-stage timings; writes a PNG and an MP4 into the directory given
// as argv[1] (default /tmp). Usage: render_speed [dir] [frames] [aa 0/1] [shadows 0/1] [ab [all|smooth|contact]]
// With "ab": no video; two renderers of the same scene, one with the look's extra passes off
// (RenderSettings::smoothSilhouettes, contactShadows) and one with them on, draw alternate
// frames (interleaved, so both see the same machine); prints the median drawing time of each
// (updateDynamicMesh + render, which waits for the GL work to finish).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "render/image.h"
#include "render/mesh_builders.h"
#include "render/renderer.h"
#include "render/video_encoder.h"

using namespace springy::render;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}
// The sample scene: ground, gallows, crate and a ~5k-triangle jelly ball; returns the ball's id.
MeshId buildScene(Renderer& r, const MeshData& ball) {
  r.addGround({0, 0, 0}, {0, 1, 0}, 40.0f);
  MeshData gallows = makeCylinder({-1.2f, 0.0f, 0.0f}, {-1.2f, 3.0f, 0.0f}, 0.08f);
  appendMesh(gallows, makeCylinder({-1.3f, 2.9f, 0.0f}, {0.4f, 2.9f, 0.0f}, 0.07f));
  Material wood;
  wood.colour = {0.45f, 0.30f, 0.18f};
  wood.specular = 0.05f;
  r.addStaticMesh(gallows, wood);
  Material crate;
  crate.colour = {0.30f, 0.45f, 0.75f};
  r.addStaticMesh(makeBox({1.5f, 0.4f, -0.8f}, glm::vec3(0.4f)), crate);
  Material jelly;
  jelly.colour = {0.95f, 0.35f, 0.55f};
  jelly.alpha = 0.7f;
  jelly.shininess = 64.0f;
  jelly.specular = 0.5f;
  const MeshId id = r.addDynamicMesh(ball.vertexCount(), ball.indices, jelly);
  r.setCamera(frameBounds({-1.5f, 0.0f, -1.5f}, {2.0f, 3.0f, 1.5f}, r.aspect(), 40.0f, 25.0f, 15.0f));
  return id;
}

// The ball squashed and stretched at frame f.
void squashBall(const MeshData& ball, int f, std::vector<float>& pos) {
  pos.resize(ball.positions.size());
  const float t = static_cast<float>(f) / 30.0f;
  const float squash = 1.0f + 0.25f * std::sin(t * 9.0f);
  for (std::size_t i = 0; i < pos.size(); i += 3) {
    pos[i] = ball.positions[i] / std::sqrt(squash) + 0.3f;
    pos[i + 1] = ball.positions[i + 1] * squash + 0.6f * squash + 0.2f;
    pos[i + 2] = ball.positions[i + 2] / std::sqrt(squash);
  }
}

// which: "all", "smooth" (smoothSilhouettes only) or "contact" (contactShadows only) is what
// the "off" renderer leaves out.
int abTiming(RenderSettings s, int frames, const std::string& which, int rings, int segments) {
  const MeshData ball = makeSphere({0.0f, 0.0f, 0.0f}, 0.6f, rings, segments);
  RenderSettings off = s;
  off.smoothSilhouettes = which == "contact";
  off.contactShadows = which == "smooth";
  Renderer a(off), b(s);
  const MeshId ia = buildScene(a, ball), ib = buildScene(b, ball);
  std::vector<double> ms[2];
  std::vector<float> pos;
  for (int f = 0; f < frames; ++f) {
    squashBall(ball, f, pos);
    for (int k = 0; k < 2; ++k) {
      Renderer& r = k == 0 ? a : b;
      const auto t0 = std::chrono::steady_clock::now();
      r.updateDynamicMesh(k == 0 ? ia : ib, pos);
      r.render();
      const double elapsed = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (f > 0) ms[k].push_back(elapsed);  // the first frame compiles shaders
    }
    if (f == frames - 1) {
      const std::string tag = std::to_string(ball.indices.size() / 3);
      writePng("/tmp/springy_render_speed_look_off_" + tag + ".png", a.readImage());
      writePng("/tmp/springy_render_speed_look_on_" + tag + ".png", b.readImage());
    }
  }
  const double before = median(ms[0]), after = median(ms[1]);
  std::printf(
      "%dx%d, ball of %zu triangles, %d frames each, interleaved; median drawing ms (upload + render): look "
      "passes off %.2f, on %.2f (%+.1f%%; off: %s)\n",
      s.width, s.height, ball.indices.size() / 3, frames - 1, before, after, 100.0 * (after / before - 1.0),
      which == "all" ? "smooth silhouettes and contact shadows" : which.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : "/tmp";
  const int frames = argc > 2 ? std::max(2, std::stoi(argv[2])) : 30;
  RenderSettings s;
  s.width = 1280;
  s.height = 720;
  s.antiAlias = argc > 3 ? std::stoi(argv[3]) != 0 : true;
  s.shadows = argc > 4 ? std::stoi(argv[4]) != 0 : true;
  if (argc > 5 && std::string(argv[5]) == "ab") {
    // The sample's fine ball (drawn as it is), then a coarse one (as the 146-vertex ball; refined).
    abTiming(s, frames, argc > 6 ? argv[6] : "all", 50, 50);
    return abTiming(s, frames, argc > 6 ? argv[6] : "all", 9, 18);
  }
  Renderer r(s);
  std::printf("%s, AA %s, shadows %s\n", r.glInfo().c_str(), s.antiAlias ? "on" : "off", s.shadows ? "on" : "off");

  const MeshData ball = makeSphere({0.0f, 0.0f, 0.0f}, 0.6f, 50, 50);  // ~4.9k triangles
  const MeshId id = buildScene(r, ball);
  std::printf("dynamic mesh: %zu vertices, %zu triangles\n", ball.vertexCount(), ball.indices.size() / 3);

  VideoEncoder enc;
  VideoEncoder::setLibraryLogging(false);
  enc.open(dir + "/springy_render_speed.mp4", s.width, s.height, 30, 20, "veryfast");
  std::vector<double> render, readback, convert, encode;
  std::vector<std::uint8_t> rgba;
  std::vector<float> pos(ball.positions.size());
  std::chrono::steady_clock::time_point loopStart;
  for (int f = 0; f < frames; ++f) {
    if (f == 1) loopStart = std::chrono::steady_clock::now();
    const float t = static_cast<float>(f) / 30.0f;
    squashBall(ball, f, pos);
    r.updateDynamicMesh(id, pos);
    char line[64];
    std::snprintf(line, sizeof line, "t = %.2f s", static_cast<double>(t));
    r.setOverlayText({"jelly on the gallows", line, "implicit Euler, dt = 1 ms"});
    r.render();
    r.readPixels(rgba);
    enc.writeFrame(rgba);
    if (f == 0) continue;  // first frame compiles shaders
    render.push_back(r.timings().renderMs);
    readback.push_back(r.timings().readbackMs);
    convert.push_back(enc.timings().convertMs);
    encode.push_back(enc.timings().encodeMs);
  }
  enc.finish();
  const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - loopStart).count();
  writePng(dir + "/springy_render_speed.png", s.width, s.height, rgba);
  std::printf("codec %s; medians over %d frames (ms): render %.1f  readback %.2f  convert %.2f  "
              "encode %.1f\n",
              enc.codecName().c_str(), frames - 1, median(render), median(readback),
              median(convert), median(encode));
  std::printf("encode incl. flush, per frame: %.1f ms; whole loop incl. flush: %.1f ms/frame = %.1f fps\n",
              enc.timings().totalEncodeMs / frames, wall / (frames - 1), 1000.0 * (frames - 1) / wall);
  return 0;
}

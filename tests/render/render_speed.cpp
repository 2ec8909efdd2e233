// Not a test: renders a representative 1280x720 scene (ground, gallows, a deforming ~5k-triangle
// jelly, overlay) and prints per-stage timings; writes a PNG and an MP4 into the directory given
// as argv[1] (default /tmp). Usage: render_speed [dir] [frames] [aa 0/1] [shadows 0/1]
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
}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : "/tmp";
  const int frames = argc > 2 ? std::max(2, std::stoi(argv[2])) : 30;
  RenderSettings s;
  s.width = 1280;
  s.height = 720;
  s.antiAlias = argc > 3 ? std::stoi(argv[3]) != 0 : true;
  s.shadows = argc > 4 ? std::stoi(argv[4]) != 0 : true;
  Renderer r(s);
  std::printf("%s, AA %s, shadows %s\n", r.glInfo().c_str(), s.antiAlias ? "on" : "off",
              s.shadows ? "on" : "off");

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

  const MeshData ball = makeSphere({0.0f, 0.0f, 0.0f}, 0.6f, 50, 50);  // ~4.9k triangles
  Material jelly;
  jelly.colour = {0.95f, 0.35f, 0.55f};
  jelly.alpha = 0.7f;
  jelly.shininess = 64.0f;
  jelly.specular = 0.5f;
  const MeshId id = r.addDynamicMesh(ball.vertexCount(), ball.indices, jelly);
  std::printf("dynamic mesh: %zu vertices, %zu triangles\n", ball.vertexCount(), ball.indices.size() / 3);

  r.setCamera(frameBounds({-1.5f, 0.0f, -1.5f}, {2.0f, 3.0f, 1.5f}, r.aspect(), 40.0f, 25.0f, 15.0f));

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
    const float squash = 1.0f + 0.25f * std::sin(t * 9.0f);
    for (std::size_t i = 0; i < pos.size(); i += 3) {
      pos[i] = ball.positions[i] / std::sqrt(squash) + 0.3f;
      pos[i + 1] = ball.positions[i + 1] * squash + 0.6f * squash + 0.2f;
      pos[i + 2] = ball.positions[i + 2] / std::sqrt(squash);
    }
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

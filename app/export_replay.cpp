// The 3D replay of a report page (app/report.cpp): a classic script, REPLAY.js, that sets two
// globals for the page's viewer (app/report/viewer.js):
//   springyReplayData    the scene: per body its name, colour, vertex count, quantum and triangles;
//                        the visible colliders as meshes at rest, with their poses at the kept
//                        frames where they move (and the props that move); the camera the scene
//                        gives; the frame rate and count
//   springyReplayMotion  every kept frame's positions, deflated (zlib, RFC 1950) and in base64
// A script, not a file the page fetches: a page opened from a folder (file://) may not fetch
// files, but it may load scripts. The positions are quantized to 1/16384 of each body's size at
// rest (2 m: 0.12 mm, under a pixel of any view of the body) as 32-bit integers, frame 0 as they
// are and each later frame as its change from the one before: smooth motion makes small numbers
// that deflate well (a 2562-vertex ball bouncing for 12 s at 15 frames/s: about a tenth of the raw
// floats). Frames are kept at most 15 a second (every k-th of the run's).
//
// Streams: the deflated frames go to a spill file as they come, and commit() writes the script,
// encoding the spill file's bytes as base64 chunk by chunk; memory does not grow with the run.
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "app/atomic_file.h"
#include "app/export.h"
#include "app/spill_file.h"
#include "sim/error.h"

namespace springy {
namespace {

constexpr double kMaxReplayFps = 15.0;
constexpr double kQuantaPerSize = 16384.0;

// Base64 (RFC 4648) of `size` bytes, appended to `out`.
void appendBase64(const uint8_t* data, std::size_t size, std::string& out) {
  static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::size_t i = 0;
  for (; i + 3 <= size; i += 3) {
    const uint32_t n = (uint32_t{data[i]} << 16) | (uint32_t{data[i + 1]} << 8) | data[i + 2];
    out += kDigits[n >> 18], out += kDigits[(n >> 12) & 63], out += kDigits[(n >> 6) & 63], out += kDigits[n & 63];
  }
  if (i < size) {
    const uint32_t n = (uint32_t{data[i]} << 16) | (i + 1 < size ? uint32_t{data[i + 1]} << 8 : 0u);
    out += kDigits[n >> 18], out += kDigits[(n >> 12) & 63];
    out += i + 1 < size ? kDigits[(n >> 6) & 63] : '=';
    out += '=';
  }
}

template <typename T>
std::string base64Of(const std::vector<T>& values) {
  std::string out;
  appendBase64(reinterpret_cast<const uint8_t*>(values.data()), values.size() * sizeof(T), out);
  return out;
}

nlohmann::json vec(const Vec3& v) { return {v.x, v.y, v.z}; }

class ReplayExport final : public MotionExport {
 public:
  ReplayExport(const std::string& path, const SceneDesc& scene, const World& world, long frames, double frameTime,
               const std::vector<std::string>& inputs)
      : output_(path, inputs), spill_(path), bodies_(exportBodies(scene, world)) {
    stride_ = std::max(1L, static_cast<long>(std::ceil(1.0 / (frameTime * kMaxReplayFps) - 1e-9)));
    kept_ = frames / stride_ + 1;
    std::memset(&zs_, 0, sizeof zs_);
    if (deflateInit(&zs_, 6) != Z_OK) throw Error(path + ": zlib could not start");
    zlibOpen_ = true;
    nlohmann::json bodies = nlohmann::json::array();
    for (const ExportBody& b : bodies_) {
      const BodyInfo& info = world.model().bodies[b.body];
      const double quantum = (info.restSize > 0.0 ? info.restSize : 1.0) / kQuantaPerSize;
      quanta_.push_back(quantum);
      std::vector<uint32_t> indices;
      for (const Triangle& t : b.triangles) indices.insert(indices.end(), t.begin(), t.end());
      bodies.push_back({{"name", b.name},
                        {"color", vec(linearColor(b.look.color))},
                        {"alpha", b.look.alpha},
                        {"flat", b.look.flat},
                        {"open", info.open},
                        {"vertices", b.vertexCount()},
                        {"quantum", quantum},
                        {"triangles", base64Of(indices)}});
      points_ += b.vertexCount();
    }
    nlohmann::json stills = nlohmann::json::array();
    for (const ColliderMesh& m : colliderMeshes(scene, world)) {
      std::vector<float> xyz(m.xyz.begin(), m.xyz.end());
      if (m.moves()) moving_.push_back({stills.size(), m.motion});
      stills.push_back({{"name", m.name},
                        {"color", vec(linearColor(m.look.color))},
                        {"alpha", m.look.alpha},
                        {"xyz", base64Of(xyz)},
                        {"triangles", base64Of(m.indices)}});
    }
    const CameraDesc& camera = scene.view.render.camera;
    header_ = {{"format", "springy-replay 1"},
               {"scene", scene.name},
               {"fps", 1.0 / (frameTime * static_cast<double>(stride_))},
               {"frames", kept_},
               {"duration", frameTime * static_cast<double>(frames)},
               {"bodies", std::move(bodies)},
               {"stills", std::move(stills)},
               {"camera",
                {{"position", camera.position ? vec(*camera.position) : nlohmann::json()},
                 {"target", camera.target ? vec(*camera.target) : nlohmann::json()},
                 {"fov", camera.fov}}},
               {"sky", {vec(scene.view.render.skyTop), vec(scene.view.render.skyBottom)}}};
    last_.assign(3 * points_, 0);
  }

  ~ReplayExport() override {
    if (zlibOpen_) deflateEnd(&zs_);
  }

  void frame(const World& world, const Monitor&) override {
    if (seen_++ % stride_ != 0) return;
    delta_.resize(3 * points_);
    std::size_t k = 0;
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      drawnPositions(bodies_[i], world, xyz_);
      for (double c : xyz_) {
        const double q = std::nearbyint(c / quanta_[i]);
        // |q| < 2^30: every change between frames fits 32 bits.
        if (!(std::abs(q) < 1073741824.0)) {
          throw Error(output_.target() + ": body '" + bodies_[i].name + "' is too far from the origin for the replay (" +
                      std::to_string(c) + " m)");
        }
        const auto now = static_cast<int32_t>(q);
        delta_[k] = now - last_[k];
        last_[k++] = now;
      }
    }
    deflateSome(reinterpret_cast<const uint8_t*>(delta_.data()), delta_.size() * sizeof(int32_t), Z_NO_FLUSH);
    if (!moving_.empty()) times_.push_back(world.time());
    ++written_;
  }

  void commit() override {
    if (written_ != kept_) {
      throw Error(output_.target() + ": " + std::to_string(written_) + " frames written of " + std::to_string(kept_) +
                  "; not written");
    }
    deflateSome(nullptr, 0, Z_FINISH);
    addPoses();
    output_.write("// springy report: the 3D replay of " + header_["scene"].get<std::string>() +
                  " (app/export_replay.cpp)\nwindow.springyReplayData = " + header_.dump() +
                  ";\nwindow.springyReplayMotion = \"");
    std::string text;
    spill_.read([&](const uint8_t* data, std::size_t size) {
      text.clear();
      appendBase64(data, size, text);
      output_.write(text);
    });
    output_.write("\";\n");
    output_.commit();
  }

  std::string written() const override { return output_.target(); }

 private:
  void deflateSome(const uint8_t* data, std::size_t size, int flush) {
    zs_.next_in = const_cast<Bytef*>(data);
    zs_.avail_in = static_cast<uInt>(size);
    uint8_t out[1 << 16];
    for (;;) {
      zs_.next_out = out;
      zs_.avail_out = sizeof out;
      const int status = deflate(&zs_, flush);
      if (status == Z_STREAM_ERROR) throw Error(output_.target() + ": zlib failed");
      spill_.write(out, sizeof out - zs_.avail_out);
      if (flush == Z_FINISH ? status == Z_STREAM_END : zs_.avail_out != 0) break;
    }
  }

  // A moving collider's or prop's poses at the kept frames (at each one's simulated time, where
  // the bodies are), added to its mesh at rest: "translations" (x, y, z per frame) and, where it
  // turns, "rotations" (the quaternion's x, y, z, w per frame): three.js's position and quaternion
  // of its mesh, as 32-bit floats in base64.
  void addPoses() {
    for (const Moving& m : moving_) {
      std::vector<float> translations, rotations;
      posesAt(m.motion, times_, translations, rotations);
      header_["stills"][m.still]["translations"] = base64Of(translations);
      if (m.motion.spin != 0.0) header_["stills"][m.still]["rotations"] = base64Of(rotations);
    }
  }

  struct Moving {
    std::size_t still;  // in the header's stills
    Movement motion;
  };
  AtomicFile output_;
  SpillFile spill_;
  std::vector<ExportBody> bodies_;
  std::vector<Moving> moving_;
  std::vector<double> times_;  // the kept frames' simulated times, when something moves
  std::vector<double> quanta_;
  std::size_t points_ = 0;
  long stride_ = 1, kept_ = 0, seen_ = 0, written_ = 0;
  nlohmann::json header_;
  z_stream zs_;
  bool zlibOpen_ = false;
  std::vector<int32_t> last_, delta_;
  std::vector<double> xyz_;
};

}  // namespace

std::unique_ptr<MotionExport> openReplay(const std::string& path, const SceneDesc& scene, const World& world,
                                         long frames, double frameTime, const std::vector<std::string>& inputs) {
  return std::make_unique<ReplayExport>(path, scene, world, frames, frameTime, inputs);
}

}  // namespace springy

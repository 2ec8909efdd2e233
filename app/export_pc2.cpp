// The point cache: FILE.pc2 (every frame's points) and FILE.obj + FILE.mtl (the bodies at the first
// frame as one object, vertex k of the object point k of the cache). PC2 is the point-cache format
// of 3ds Max that Blender's Mesh Cache modifier reads: a 32-byte header ("POINTCACHE2\0", version
// 1, the point count, the first frame, frames per sample, the sample count), then x, y, z as
// little-endian 32-bit floats per point per sample.
#include <cctype>
#include <cstdio>
#include <limits>
#include <cstring>
#include <filesystem>

#include "app/atomic_file.h"
#include "app/export.h"
#include "sim/error.h"

namespace springy {
namespace {

static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559);

// A name that OBJ and MTL keep as one word.
std::string objName(uint32_t index, const std::string& name) {
  std::string out = "body" + std::to_string(index);
  if (name.empty()) return out;
  out += "_";
  for (char c : name) out += std::isgraph(static_cast<unsigned char>(c)) && c != '#' ? c : '_';
  return out;
}

class PointCacheExport final : public MotionExport {
 public:
  PointCacheExport(const std::string& path, const SceneDesc& scene, const World& world, long frames,
                   double frameTime, const std::vector<std::string>& inputs)
      : scene_(scene), frames_(frames), bodies_(exportBodies(scene, world)) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    objPath_ = fs::path(target).replace_extension(".obj").string();
    mtlPath_ = fs::path(target).replace_extension(".mtl").string();
    // All three are created now: a directory that cannot take them fails before the run.
    cache_ = std::make_unique<AtomicFile>(path, inputs);
    obj_ = std::make_unique<AtomicFile>(objPath_, inputs);
    mtl_ = std::make_unique<AtomicFile>(mtlPath_, inputs);
    for (const ExportBody& b : bodies_) points_ += b.vertexCount();
    if (points_ > static_cast<std::size_t>(INT32_MAX)) throw Error(path + ": too many points for a PC2 file");
    unsigned char header[32] = {};
    std::memcpy(header, "POINTCACHE2", 12);
    const int32_t version = 1, count = static_cast<int32_t>(points_), samples = static_cast<int32_t>(frames + 1);
    const float start = 0.0f, rate = 1.0f;  // sample k is frame k (Blender's frames, at the scene's rate)
    std::memcpy(header + 12, &version, 4);
    std::memcpy(header + 16, &count, 4);
    std::memcpy(header + 20, &start, 4);
    std::memcpy(header + 24, &rate, 4);
    std::memcpy(header + 28, &samples, 4);
    cache_->write({header, sizeof header});
    (void)frameTime;
  }

  void frame(const World& world, const Monitor&) override {
    std::vector<float> sample;
    sample.reserve(3 * points_);
    for (const ExportBody& b : bodies_) {
      drawnPositions(b, world, xyz_);
      for (double c : xyz_) sample.push_back(static_cast<float>(c));
    }
    if (written_ == 0) writeObj(sample);
    cache_->write({reinterpret_cast<const uint8_t*>(sample.data()), sample.size() * sizeof(float)});
    ++written_;
  }

  void commit() override {
    if (written_ != frames_ + 1) {
      throw Error(cache_->target() + ": " + std::to_string(written_) + " frames written of " +
                  std::to_string(frames_ + 1) + "; not written");
    }
    mtl_->commit();
    obj_->commit();
    cache_->commit();
  }

  std::string written() const override { return cache_->target() + " with " + objPath_ + " and " + mtlPath_; }

 private:
  // The first frame as an OBJ whose vertices are the cache's points, in order: one object
  // ("o springy"; Blender's importer keeps one object's vertices in the file's order), a group
  // and a material per body.
  void writeObj(const std::vector<float>& sample) {
    namespace fs = std::filesystem;
    std::string text = "# springy export of " + scene_.path + " (" + scene_.name + "): " +
                       std::to_string(bodies_.size()) + " bodies, " + std::to_string(points_) +
                       " points, the first of " + std::to_string(frames_ + 1) + " frames; " +
                       fs::path(cache_->target()).filename().string() + " holds them all\n";
    text += "mtllib " + fs::path(mtlPath_).filename().string() + "\no springy\n";
    char line[160];
    for (std::size_t k = 0; k < points_; ++k) {
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", sample[3 * k], sample[3 * k + 1], sample[3 * k + 2]);
      text += line;
    }
    std::string materials = "# springy export: the bodies' colours\n";
    std::size_t first = 1;  // OBJ counts from 1
    for (const ExportBody& b : bodies_) {
      const std::string name = objName(b.body, b.name);
      text += "g " + name + "\nusemtl " + name + "\n";
      for (const Triangle& t : b.triangles) {
        std::snprintf(line, sizeof line, "f %zu %zu %zu\n", first + t[0], first + t[1], first + t[2]);
        text += line;
      }
      first += b.vertexCount();
      const Material& m = b.look;
      const Vec3 kd = linearColor(m.color);  // Blender's importer takes Kd as the linear base colour
      std::snprintf(line, sizeof line, "Kd %.6g %.6g %.6g\nd %.6g\nNs %.6g\n", kd.x, kd.y, kd.z, m.alpha, m.shininess);
      materials += "newmtl " + name + "\n" + line;
    }
    obj_->write(text);
    mtl_->write(materials);
  }

  const SceneDesc& scene_;
  long frames_;
  std::vector<ExportBody> bodies_;
  std::size_t points_ = 0;
  std::string objPath_, mtlPath_;
  std::unique_ptr<AtomicFile> cache_, obj_, mtl_;
  std::vector<double> xyz_;
  long written_ = 0;
};

}  // namespace

std::unique_ptr<MotionExport> openPointCache(const std::string& path, const SceneDesc& scene, const World& world,
                                             long frames, double frameTime, const std::vector<std::string>& inputs) {
  return std::make_unique<PointCacheExport>(path, scene, world, frames, frameTime, inputs);
}

}  // namespace springy

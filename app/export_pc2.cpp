// The point cache: FILE.pc2 (every frame's points) and FILE.obj + FILE.mtl (the bodies at the first
// frame as one object, vertex k of the object point k of the cache). A collider or prop that
// moves is an object of its own in the OBJ with a cache of its own, FILE.collider0.pc2 (Blender's
// Mesh Cache modifier reads one file per object). PC2 is the point-cache format
// of 3ds Max that Blender's Mesh Cache modifier reads: a 32-byte header ("POINTCACHE2\0", version
// 1, the point count, the first frame, frames per sample, the sample count), then x, y, z as
// little-endian 32-bit floats per point per sample.
#include <cctype>
#include <cstdio>
#include <limits>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <sys/stat.h>

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

// A PC2 file's header: `points` per sample, `samples` samples; sample k is frame k (Blender's
// frames, at the scene's rate).
void writeHeader(AtomicFile& cache, std::size_t points, long samples) {
  if (points > static_cast<std::size_t>(INT32_MAX)) throw Error(cache.target() + ": too many points for a PC2 file");
  unsigned char header[32] = {};
  std::memcpy(header, "POINTCACHE2", 12);
  const int32_t version = 1, count = static_cast<int32_t>(points), sampleCount = static_cast<int32_t>(samples);
  const float start = 0.0f, rate = 1.0f;
  std::memcpy(header + 12, &version, 4);
  std::memcpy(header + 16, &count, 4);
  std::memcpy(header + 20, &start, 4);
  std::memcpy(header + 24, &rate, 4);
  std::memcpy(header + 28, &sampleCount, 4);
  cache.write({header, sizeof header});
}

// A sample of a PC2 file: the points as 32-bit floats.
void writeSample(AtomicFile& cache, const std::vector<float>& sample) {
  cache.write({reinterpret_cast<const uint8_t*>(sample.data()), sample.size() * sizeof(float)});
}

// A material of the MTL file.
std::string mtlEntry(const std::string& name, const Material& m) {
  const Vec3 kd = linearColor(m.color);  // Blender's importer takes Kd as the linear base colour
  char line[160];
  std::snprintf(line, sizeof line, "Kd %.6g %.6g %.6g\nd %.6g\nNs %.6g\n", kd.x, kd.y, kd.z, m.alpha, m.shininess);
  return "newmtl " + name + "\n" + line;
}

// The first bytes of the files springy writes beside a cache: what tells them from a user's.
constexpr std::string_view kCompanionHeader = "# springy export";
constexpr std::string_view kCacheHeader{"POINTCACHE2\0", 12};

// A file the cache `cache` is written with (its .obj, .mtl, a moving collider's cache), named by the
// cache's name and not by the user: it may replace neither an input of the run nor a file that
// springy did not write (`springys`: whether the existing file is springy's). Throws springy::Error.
void checkCompanion(const std::string& cache, const std::string& companion, const std::vector<std::string>& inputs,
                    bool springys) {
  namespace fs = std::filesystem;
  const std::string why = cache + " is written with " + companion + " beside it";
  const std::string other = (fs::path(cache).parent_path() / (fs::path(cache).stem().string() + "_motion.pc2")).string();
  for (const std::string& input : inputs) {
    if (sameFile(companion, input)) {
      throw Error(companion + ": is the input file '" + input + "' (" + why +
                  "); refusing to write over it. Name the export otherwise, e.g. -o " + other);
    }
  }
  struct stat st {};
  if (!springys && ::stat(companion.c_str(), &st) == 0) {
    throw Error(companion + ": exists and was not written by springy (" + why +
                "); refusing to replace it. Move it away, or name the export otherwise, e.g. -o " + other);
  }
}

class PointCacheExport final : public MotionExport {
 public:
  PointCacheExport(const std::string& path, const SceneDesc& scene, const World& world, long frames,
                   double frameTime, const std::vector<std::string>& inputs)
      : scene_(scene), frames_(frames), bodies_(exportBodies(scene, world)), moving_(movingMeshes(scene, world)) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    objPath_ = fs::path(target).replace_extension(".obj").string();
    mtlPath_ = fs::path(target).replace_extension(".mtl").string();
    // The files beside the cache replace only springy's own: an OBJ and MTL it wrote begin with its
    // header; a moving collider's cache is a PC2 that the springy OBJ beside it names.
    const std::string oldObj = firstBytes(objPath_, 1 << 16);
    const bool objSpringys = oldObj.rfind(kCompanionHeader, 0) == 0;
    checkCompanion(path, objPath_, inputs, objSpringys);
    checkCompanion(path, mtlPath_, inputs, firstBytes(mtlPath_, kCompanionHeader.size()) == kCompanionHeader);
    std::vector<std::string> movingNames;
    for (const ColliderMesh& m : moving_) {
      const std::string name = fs::path(target).replace_extension("." + m.word() + ".pc2").string();
      const std::string file = fs::path(name).filename().string();
      checkCompanion(path, name, inputs,
                     firstBytes(name, kCacheHeader.size()) == kCacheHeader && objSpringys &&
                         oldObj.find(" " + file + "\n") != std::string::npos);
      movingNames.push_back(name);
    }
    // All are created now: a directory that cannot take them fails before the run.
    cache_ = std::make_unique<AtomicFile>(path, inputs);
    obj_ = std::make_unique<AtomicFile>(objPath_, inputs);
    mtl_ = std::make_unique<AtomicFile>(mtlPath_, inputs);
    for (const ExportBody& b : bodies_) points_ += b.vertexCount();
    writeHeader(*cache_, points_, frames + 1);
    // A cache per moving collider or prop, beside the bodies': FILE.collider0.pc2.
    for (std::size_t j = 0; j < moving_.size(); ++j) {
      auto& cache = movingCaches_.emplace_back(std::make_unique<AtomicFile>(movingNames[j], inputs));
      writeHeader(*cache, moving_[j].xyz.size() / 3, frames + 1);
    }
    (void)frameTime;
  }

  void frame(const World& world, const Monitor&) override {
    std::vector<float> sample;
    sample.reserve(3 * points_);
    for (const ExportBody& b : bodies_) {
      drawnPositions(b, world, xyz_);
      for (double c : xyz_) sample.push_back(static_cast<float>(c));
    }
    std::vector<std::vector<float>> placed;
    for (std::size_t j = 0; j < moving_.size(); ++j) {
      moving_[j].placed(world.time(), xyz_);
      placed.emplace_back(xyz_.begin(), xyz_.end());
      writeSample(*movingCaches_[j], placed.back());
    }
    if (written_ == 0) writeObj(sample, placed);
    writeSample(*cache_, sample);
    ++written_;
  }

  void commit() override {
    if (written_ != frames_ + 1) {
      throw Error(cache_->target() + ": " + std::to_string(written_) + " frames written of " +
                  std::to_string(frames_ + 1) + "; not written");
    }
    mtl_->commit();
    obj_->commit();
    for (auto& c : movingCaches_) c->commit();
    cache_->commit();
  }

  std::string written() const override {
    std::string out = cache_->target() + " with " + objPath_;
    for (const auto& c : movingCaches_) out += ", " + c->target();
    return out + " and " + mtlPath_;
  }

 private:
  // The first frame as an OBJ whose vertices are the cache's points, in order: one object
  // ("o springy"; Blender's importer keeps one object's vertices in the file's order), a group
  // and a material per body; then an object per moving collider or prop ("o collider0"), its
  // vertices its own cache's points.
  void writeObj(const std::vector<float>& sample, const std::vector<std::vector<float>>& placed) {
    namespace fs = std::filesystem;
    std::string text = "# springy export of " + scene_.path + " (" + scene_.name + "): " +
                       std::to_string(bodies_.size()) + " bodies, " + std::to_string(points_) +
                       " points, the first of " + std::to_string(frames_ + 1) + " frames; " +
                       fs::path(cache_->target()).filename().string() + " holds them all\n";
    // Each moving object's cache is named, one a line: the next export knows them as springy's.
    if (!moving_.empty()) {
      text += "# then each collider and prop that moves (" + std::to_string(moving_.size()) +
              "): an object, whose points a cache of its own holds:\n";
      for (const auto& c : movingCaches_) text += "#   " + fs::path(c->target()).filename().string() + "\n";
    }
    text += "mtllib " + fs::path(mtlPath_).filename().string() + "\no springy\n";
    appendVertices(sample, text);
    std::string materials = "# springy export: the bodies' colours\n";
    std::size_t first = 1;  // OBJ counts from 1
    for (const ExportBody& b : bodies_) {
      const std::string name = objName(b.body, b.name);
      text += "g " + name + "\nusemtl " + name + "\n";
      for (const Triangle& t : b.triangles) appendFace(first, t.data(), text);
      first += b.vertexCount();
      materials += mtlEntry(name, b.look);
    }
    for (std::size_t j = 0; j < moving_.size(); ++j) {
      const ColliderMesh& m = moving_[j];
      text += "o " + m.word() + "\n";
      appendVertices(placed[j], text);
      text += "usemtl " + m.word() + "\n";
      for (std::size_t i = 0; i + 2 < m.indices.size(); i += 3) appendFace(first, &m.indices[i], text);
      first += m.xyz.size() / 3;
      materials += mtlEntry(m.word(), m.look);
    }
    obj_->write(text);
    mtl_->write(materials);
  }
  static void appendVertices(const std::vector<float>& xyz, std::string& text) {
    char line[160];
    for (std::size_t k = 0; k + 2 < xyz.size(); k += 3) {
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", xyz[k], xyz[k + 1], xyz[k + 2]);
      text += line;
    }
  }
  static void appendFace(std::size_t first, const uint32_t* t, std::string& text) {
    char line[160];
    std::snprintf(line, sizeof line, "f %zu %zu %zu\n", first + t[0], first + t[1], first + t[2]);
    text += line;
  }

  const SceneDesc& scene_;
  long frames_;
  std::vector<ExportBody> bodies_;
  std::vector<ColliderMesh> moving_;
  std::vector<std::unique_ptr<AtomicFile>> movingCaches_;  // parallel to moving_
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

// ParaView's time series: FILE.pvd (a VTK "Collection": each body's file at each frame's time,
// the body its part) and the folder FILE/ beside it with one .vtu (VTK XML unstructured grid,
// triangles) per body and frame: the points in 64-bit floats and, per point, velocity, strain,
// contact, pinned and, for a body drawn with its simulated mesh, mass; the time and the body's
// volume as field data. Each collider or prop that moves has a series of its own
// (FILE/collider0_NNNNNN.vtu: its points where its motion has it at the frame's time, the time as
// field data), listed per frame after the bodies, each its own part, in the group "colliders".
// Binary data are appended raw after the XML (header_type UInt64: each array's byte count, then
// its bytes), the layout VTK's own writer uses.
//
// The folder is built under a temporary name beside it and renamed when the run is complete; a
// folder of an earlier export is replaced then, one that springy did not make (no marker file
// in it), or that holds files it did not write or an input of the run, is refused before the run
// (app/folder.h).
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "app/atomic_file.h"
#include "run/records.h"
#include "app/export.h"
#include "app/folder.h"
#include "sim/error.h"

namespace springy {
namespace {

constexpr const char* kMarker = ".springy-series";  // in every folder springy writes

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

// Appended raw data: the blocks and the XML elements that point into them.
struct Appended {
  std::vector<uint8_t> bytes;
  // Adds a block (its count, then its bytes); returns its offset.
  uint64_t add(const void* data, uint64_t size) {
    const uint64_t at = bytes.size();
    const auto* p = static_cast<const uint8_t*>(data);
    bytes.insert(bytes.end(), reinterpret_cast<const uint8_t*>(&size), reinterpret_cast<const uint8_t*>(&size) + 8);
    bytes.insert(bytes.end(), p, p + size);
    return at;
  }
  template <typename T>
  uint64_t add(const std::vector<T>& v) {
    return add(v.data(), v.size() * sizeof(T));
  }
};

std::string arrayXml(const char* type, const char* name, int components, uint64_t offset) {
  std::string s = std::string("<DataArray type=\"") + type + "\"";
  if (name) s += std::string(" Name=\"") + name + "\"";
  if (components > 1) s += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  return s + " format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
}

// A mesh's triangles as the .vtu's cells, written once: connectivity, offsets and types.
struct Cells {
  Appended data;
  uint64_t connectivity = 0, offsets = 0, types = 0;
  std::size_t count = 0;
  std::vector<double> mass;  // per point, for a body drawn with its simulated mesh; else empty

  explicit Cells(const std::vector<uint32_t>& indices) : count(indices.size() / 3) {
    const std::vector<int64_t> vertices(indices.begin(), indices.end());
    std::vector<int64_t> ends;
    for (std::size_t k = 3; k <= vertices.size(); k += 3) ends.push_back(static_cast<int64_t>(k));
    connectivity = data.add(vertices);
    offsets = data.add(ends);
    types = data.add(std::vector<uint8_t>(count, 5));  // VTK_TRIANGLE
  }
};

// A .vtu's XML up to its appended data: field data (TimeValue, then `fields`), `pointData` (a
// <PointData> element, or nothing), the points at `points` in the appended data and the cells at
// `cells` past its first `base` bytes.
std::string vtuXml(double time, const std::string& fields, std::size_t pointCount, const std::string& pointData,
                   uint64_t points, uint64_t base, const Cells& cells) {
  std::string xml =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n<UnstructuredGrid>\n<FieldData>\n";
  xml += "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">" + number(time) +
         "</DataArray>\n";
  xml += fields + "</FieldData>\n<Piece NumberOfPoints=\"" + std::to_string(pointCount) + "\" NumberOfCells=\"" +
         std::to_string(cells.count) + "\">\n" + pointData;
  xml += "<Points>\n" + arrayXml("Float64", "position", 3, points) + "</Points>\n<Cells>\n";
  xml += arrayXml("Int64", "connectivity", 1, base + cells.connectivity);
  xml += arrayXml("Int64", "offsets", 1, base + cells.offsets);
  xml += arrayXml("UInt8", "types", 1, base + cells.types);
  return xml + "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_";
}

class VtkSeriesExport final : public MotionExport {
 public:
  VtkSeriesExport(const std::string& path, const SceneDesc& scene, const World& world, long frames, double /*frameTime: each frame keeps its simulated time*/,
                  const std::vector<std::string>& inputs)
      : collection_(path, inputs), frames_(frames), bodies_(exportBodies(scene, world)), moving_(movingMeshes(scene, world)) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    folder_ = fs::path(target).replace_extension("").string();
    folderName_ = fs::path(folder_).filename().string();
    output_ = std::make_unique<OutputFolder>(
        folder_, kMarker,
        "springy export: this folder is replaced by the next export of " + fs::path(path).filename().string() + "\n",
        path + ": its frames go to the folder " + folder_, inputs);
    for (const ExportBody& b : bodies_) {
      std::vector<uint32_t> indices;
      for (const Triangle& t : b.triangles) indices.insert(indices.end(), t.begin(), t.end());
      Cells& c = cells_.emplace_back(indices);
      if (!b.embedded()) {
        for (uint32_t i : b.modelVertex) c.mass.push_back(world.model().mass[i]);
      }
    }
    for (const ColliderMesh& m : moving_) cells_.emplace_back(m.indices);
  }

  void frame(const World& world, const Monitor& monitor) override {
    for (std::size_t i = 0; i < bodies_.size(); ++i) bodyFrame(i, world, monitor);
    // A moving collider or prop: its points where its motion has it at the frame's time.
    for (std::size_t j = 0; j < moving_.size(); ++j) {
      moving_[j].placed(world.time(), xyz_);
      Appended data;
      const uint64_t points = data.add(xyz_);
      const Cells& cells = cells_[bodies_.size() + j];
      const std::string xml = vtuXml(world.time(), "", xyz_.size() / 3, "", points, data.bytes.size(), cells);
      writeFile(output_->temporaryPath() + "/" + fileName(moving_[j].word(), written_), xml, data.bytes,
                cells.data.bytes, std::string(kTail));
    }
    times_.push_back(world.time());
    ++written_;
  }

  void commit() override {
    if (written_ != frames_ + 1) {
      throw Error(collection_.target() + ": " + std::to_string(written_) + " frames written of " +
                  std::to_string(frames_ + 1) + "; not written");
    }
    std::string xml =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
        "<Collection>\n";
    // Per frame the bodies (group ""), then the moving colliders and props (group "colliders"),
    // each its own part.
    for (long k = 0; k <= frames_; ++k) {
      const std::string time = number(times_[static_cast<std::size_t>(k)]);
      for (std::size_t i = 0; i < bodies_.size(); ++i) {
        xml += dataSet(time, "", i, bodies_[i].name, fileName("body" + std::to_string(i), k));
      }
      for (std::size_t j = 0; j < moving_.size(); ++j) {
        xml += dataSet(time, "colliders", bodies_.size() + j, moving_[j].name, fileName(moving_[j].word(), k));
      }
    }
    xml += "</Collection>\n</VTKFile>\n";
    collection_.write(xml);
    output_->commit();
    collection_.commit();
  }

  std::string written() const override { return collection_.target() + " with the folder " + folder_; }

 private:
  static constexpr const char* kTail = "\n</AppendedData>\n</VTKFile>\n";

  // Body i's .vtu at this frame: its points and, per point, velocity, strain, contact, pinned and
  // mass; its volume as field data.
  void bodyFrame(std::size_t i, const World& world, const Monitor& monitor) {
    const ExportBody& b = bodies_[i];
    const BodyInfo& info = world.model().bodies[b.body];
    drawnPositions(b, world, xyz_);
    vertexFields(b, world, fields_);
    const Cells& cells = cells_[i];
    Appended data;
    const uint64_t velocity = data.add(fields_.velocity), strain = data.add(fields_.strain);
    const uint64_t contact = data.add(fields_.contact), pinned = data.add(fields_.pinned);
    const uint64_t mass = cells.mass.empty() ? 0 : data.add(cells.mass);
    const uint64_t points = data.add(xyz_);
    std::string fields;
    if (info.restVolume > 0.0) {
      fields += "<DataArray type=\"Float64\" Name=\"volume\" NumberOfTuples=\"1\" format=\"ascii\">" +
                number(monitor.records()[b.body].last.volume) + "</DataArray>\n";
      fields += "<DataArray type=\"Float64\" Name=\"rest_volume\" NumberOfTuples=\"1\" format=\"ascii\">" +
                number(info.restVolume) + "</DataArray>\n";
    }
    std::string pointData = "<PointData Vectors=\"velocity\" Scalars=\"strain\">\n";
    pointData += arrayXml("Float64", "velocity", 3, velocity);
    pointData += arrayXml("Float32", "strain", 1, strain);
    pointData += arrayXml("UInt8", "contact", 1, contact);
    pointData += arrayXml("UInt8", "pinned", 1, pinned);
    if (!cells.mass.empty()) pointData += arrayXml("Float64", "mass", 1, mass);
    pointData += "</PointData>\n";
    const std::string xml = vtuXml(world.time(), fields, b.vertexCount(), pointData, points, data.bytes.size(), cells);
    writeFile(output_->temporaryPath() + "/" + fileName("body" + std::to_string(i), written_), xml, data.bytes,
              cells.data.bytes, std::string(kTail));
  }
  std::string dataSet(const std::string& time, const char* group, std::size_t part, const std::string& name,
                      const std::string& file) const {
    return "<DataSet timestep=\"" + time + "\" group=\"" + group + "\" part=\"" + std::to_string(part) + "\" name=\"" +
           xmlEscaped(name) + "\" file=\"" + xmlEscaped(folderName_) + "/" + file + "\"/>\n";
  }
  static std::string fileName(const std::string& what, long frame) {
    char name[64];
    std::snprintf(name, sizeof name, "_%06ld.vtu", frame);
    return what + name;
  }
  [[noreturn]] void fail(const std::string& what, int error) {
    throw Error(collection_.target() + ": " + what + ": " + errorText(error) + " (" + collection_.target() +
                " left as it was)");
  }
  template <typename... Parts>
  void writeFile(const std::string& path, const Parts&... parts) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) fail("cannot create " + path, errno);
    auto put = [&](const void* data, std::size_t size) {
      const auto* p = static_cast<const uint8_t*>(data);
      while (size > 0) {
        const ssize_t n = ::write(fd, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
          const int error = n < 0 ? errno : EIO;
          ::close(fd);
          fail("writing " + path + " failed", error);
        }
        p += n, size -= static_cast<std::size_t>(n);
      }
    };
    (put(parts.data(), parts.size() * sizeof(*parts.data())), ...);
    if (::close(fd) != 0) fail("writing " + path + " failed", errno);
  }

  AtomicFile collection_;
  long frames_;
  std::vector<double> times_;  // each frame's simulated time (the step's end past the frame's instant)
  std::vector<ExportBody> bodies_;
  std::vector<ColliderMesh> moving_;
  std::vector<Cells> cells_;  // the bodies', then the moving colliders'
  std::string folder_, folderName_;
  std::unique_ptr<OutputFolder> output_;
  std::vector<double> xyz_;
  VertexFields fields_;
  long written_ = 0;
};

}  // namespace

std::unique_ptr<MotionExport> openVtkSeries(const std::string& path, const SceneDesc& scene, const World& world,
                                            long frames, double frameTime, const std::vector<std::string>& inputs) {
  return std::make_unique<VtkSeriesExport>(path, scene, world, frames, frameTime, inputs);
}

}  // namespace springy

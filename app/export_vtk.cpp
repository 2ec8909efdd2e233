// ParaView's time series: FILE.pvd (a VTK "Collection": each body's file at each frame's time,
// the body its part) and the folder FILE/ beside it with one .vtu (VTK XML unstructured grid,
// triangles) per body and frame: the points in 64-bit floats and, per point, velocity, strain,
// contact, pinned and, for a body drawn with its simulated mesh, mass; the time and the body's
// volume as field data. Binary data are appended raw after the XML (header_type UInt64: each
// array's byte count, then its bytes), the layout VTK's own writer uses.
//
// The folder is built under a temporary name beside it and renamed when the run is complete; a
// folder of an earlier export is replaced then, one that springy did not make (no marker file
// in it) is refused before the run.
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

class VtkSeriesExport final : public MotionExport {
 public:
  VtkSeriesExport(const std::string& path, const SceneDesc& scene, const World& world, long frames, double /*frameTime: each frame keeps its simulated time*/,
                  const std::vector<std::string>& inputs)
      : collection_(path, inputs), frames_(frames), bodies_(exportBodies(scene, world)) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    folder_ = fs::path(target).replace_extension("").string();
    folderName_ = fs::path(folder_).filename().string();
    output_ = std::make_unique<OutputFolder>(
        folder_, kMarker,
        "springy export: this folder is replaced by the next export of " + fs::path(path).filename().string() + "\n",
        path + ": its frames go to the folder " + folder_);
    for (const ExportBody& b : bodies_) {
      Cells& c = cells_.emplace_back();
      std::vector<int64_t> connectivity, offsets;
      for (const Triangle& t : b.triangles) {
        connectivity.insert(connectivity.end(), {t[0], t[1], t[2]});
        offsets.push_back(static_cast<int64_t>(connectivity.size()));
      }
      const std::vector<uint8_t> types(b.triangles.size(), 5);  // VTK_TRIANGLE
      c.connectivity = c.data.add(connectivity);
      c.offsets = c.data.add(offsets);
      c.types = c.data.add(types);
      if (!b.embedded()) {
        for (uint32_t i : b.modelVertex) c.mass.push_back(world.model().mass[i]);
      }
    }
  }

  void frame(const World& world, const Monitor& monitor) override {
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
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
      const uint64_t base = data.bytes.size();  // the cells' blocks follow
      std::string xml =
          "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
          "header_type=\"UInt64\">\n<UnstructuredGrid>\n<FieldData>\n";
      xml += "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">" +
             number(world.time()) + "</DataArray>\n";
      if (info.restVolume > 0.0) {
        xml += "<DataArray type=\"Float64\" Name=\"volume\" NumberOfTuples=\"1\" format=\"ascii\">" +
               number(monitor.records()[b.body].last.volume) + "</DataArray>\n";
        xml += "<DataArray type=\"Float64\" Name=\"rest_volume\" NumberOfTuples=\"1\" format=\"ascii\">" +
               number(info.restVolume) + "</DataArray>\n";
      }
      xml += "</FieldData>\n<Piece NumberOfPoints=\"" + std::to_string(b.vertexCount()) + "\" NumberOfCells=\"" +
             std::to_string(b.triangles.size()) + "\">\n<PointData Vectors=\"velocity\" Scalars=\"strain\">\n";
      xml += arrayXml("Float64", "velocity", 3, velocity);
      xml += arrayXml("Float32", "strain", 1, strain);
      xml += arrayXml("UInt8", "contact", 1, contact);
      xml += arrayXml("UInt8", "pinned", 1, pinned);
      if (!cells.mass.empty()) xml += arrayXml("Float64", "mass", 1, mass);
      xml += "</PointData>\n<Points>\n" + arrayXml("Float64", "position", 3, points) + "</Points>\n<Cells>\n";
      xml += arrayXml("Int64", "connectivity", 1, base + cells.connectivity);
      xml += arrayXml("Int64", "offsets", 1, base + cells.offsets);
      xml += arrayXml("UInt8", "types", 1, base + cells.types);
      xml += "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_";
      std::string tail = "\n</AppendedData>\n</VTKFile>\n";
      const std::string file = output_->temporaryPath() + "/" + fileName(i, written_);
      writeFile(file, xml, data.bytes, cells.data.bytes, tail);
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
    for (long k = 0; k <= frames_; ++k) {
      for (std::size_t i = 0; i < bodies_.size(); ++i) {
        xml += "<DataSet timestep=\"" + number(times_[static_cast<std::size_t>(k)]) + "\" group=\"\" part=\"" +
               std::to_string(i) + "\" name=\"" + xmlEscaped(bodies_[i].name) + "\" file=\"" + xmlEscaped(folderName_) +
               "/" + fileName(i, k) + "\"/>\n";
      }
    }
    xml += "</Collection>\n</VTKFile>\n";
    collection_.write(xml);
    output_->commit();
    collection_.commit();
  }

  std::string written() const override { return collection_.target() + " with the folder " + folder_; }

 private:
  struct Cells {
    Appended data;  // connectivity, offsets, types: the same every frame
    uint64_t connectivity = 0, offsets = 0, types = 0;
    std::vector<double> mass;  // per point; empty for an embedded mesh (its points carry none)
  };

  static std::string fileName(std::size_t body, long frame) {
    char name[64];
    std::snprintf(name, sizeof name, "body%zu_%06ld.vtu", body, frame);
    return name;
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
  std::vector<Cells> cells_;
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

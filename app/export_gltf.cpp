// glTF 2.0 binary (.glb; Khronos, "glTF 2.0 Specification", 2021): each body a mesh with its
// colour as a material and its first frame as the base shape; frame k >= 1 is morph target k - 1
// (the positions' and normals' change from the base), and an animation sets its weight to 1 at
// frame k's time, linearly between frames, so a viewer plays the run and interpolates between
// frames. The weights are a sparse accessor (one 1 per frame over zeros): frames x targets
// values would grow with the square of the run's length. The visible colliders are meshes (a
// plane as a square around the bodies); one that moves, and a prop that moves, is a node whose
// mesh is as it is at rest and whose animation sets its translation (and rotation, where it
// turns) to its pose at each frame, linearly between frames (glTF's node animation).
//
// A GLB is a 12-byte header, the JSON chunk, then the binary chunk; the JSON holds every accessor's
// range, known only at the end. So the frames' data stream to a spill file (unlinked at once, so
// nothing is left behind), and commit() writes the header and the JSON, then copies the spill file
// after them. The JSON is written with nlohmann::json: tinygltf's writer holds every buffer in
// memory (Model::buffers), which a long run's frames must not be.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>

#include "app/atomic_file.h"
#include "app/export.h"
#include "app/spill_file.h"
#include "sim/error.h"

namespace springy {
namespace {

using nlohmann::json;

constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

// Smooth vertex normals: each face's area-weighted normal summed at its corners, made unit
// (a vertex of no face, or whose faces cancel, gets +y).
void vertexNormals(const std::vector<double>& xyz, const std::vector<Triangle>& triangles, std::vector<double>& out) {
  out.assign(xyz.size(), 0.0);
  for (const Triangle& t : triangles) {
    const double* a = &xyz[3 * t[0]];
    const double* b = &xyz[3 * t[1]];
    const double* c = &xyz[3 * t[2]];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    for (uint32_t v : t) {
      for (int k = 0; k < 3; ++k) out[3 * v + k] += n[k];
    }
  }
  for (std::size_t v = 0; v < out.size() / 3; ++v) {
    double* n = &out[3 * v];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0.0 && std::isfinite(len)) {
      for (int k = 0; k < 3; ++k) n[k] /= len;
    } else {
      n[0] = 0.0, n[1] = 1.0, n[2] = 0.0;
    }
  }
}

// Float values and their range (an accessor's min and max, which glTF requires of positions and
// animation inputs and which must be the stored floats' own).
struct Floats {
  std::vector<float> values;
  std::array<float, 3> lo{}, hi{};
  void fill(const std::vector<double>& source, const std::vector<double>* minus) {
    values.resize(source.size());
    lo.fill(std::numeric_limits<float>::infinity());
    hi.fill(-std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < source.size(); ++i) {
      const float f = static_cast<float>(minus ? source[i] - (*minus)[i] : source[i]);
      values[i] = f;
      lo[i % 3] = std::min(lo[i % 3], f), hi[i % 3] = std::max(hi[i % 3], f);
    }
  }
};

json vec(const std::array<float, 3>& a) { return json::array({a[0], a[1], a[2]}); }

class GltfExport final : public MotionExport {
 public:
  GltfExport(const std::string& path, const SceneDesc& scene, const World& world, long frames, double frameTime,
             const std::vector<std::string>& inputs)
      : output_(path, inputs), spill_(path), frames_(frames), frameTime_(frameTime), bodies_(exportBodies(scene, world)) {
    doc_["asset"] = {{"version", "2.0"}, {"generator", "springy 0.1"}};
    doc_["scene"] = 0;
    doc_["scenes"] = json::array({{{"name", scene.name}, {"nodes", json::array()}}});
    for (const char* key : {"nodes", "meshes", "materials", "accessors", "bufferViews"}) doc_[key] = json::array();
    for (const ExportBody& b : bodies_) {
      std::vector<uint32_t> indices;
      indices.reserve(3 * b.triangles.size());
      for (const Triangle& t : b.triangles) indices.insert(indices.end(), t.begin(), t.end());
      Primitive p;
      p.indices = indexAccessor(indices);
      p.material = material(b.name, b.look, world.model().bodies[b.body].open);
      primitives_.push_back(p);
    }
    addColliders(scene, world);
  }

  void frame(const World& world, const Monitor&) override {
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const ExportBody& b = bodies_[i];
      Primitive& p = primitives_[i];
      drawnPositions(b, world, xyz_);
      vertexNormals(xyz_, b.triangles, normals_);
      const bool base = written_ == 0;
      if (base) base_.push_back({xyz_, normals_});
      position_.fill(xyz_, base ? nullptr : &base_[i].first);
      normal_.fill(normals_, base ? nullptr : &base_[i].second);
      // A buffer view per accessor: vertex data shared by two accessors would need a byte stride.
      const std::size_t n = b.vertexCount();
      const uint64_t positions = spill_.write(position_.values), normals = spill_.write(normal_.values);
      if (base) {
        p.position = accessor(bufferView(positions, 12 * n, kArrayBuffer), 0, n, "VEC3", &position_);
        p.normal = accessor(bufferView(normals, 12 * n, kArrayBuffer), 0, n, "VEC3", &normal_);
      } else {
        // A morph target is kept as its offsets and range; its JSON is written at commit().
        p.targets.push_back({positions, normals, position_.lo, position_.hi});
      }
    }
    if (!moving_.empty()) times_.push_back(world.time());
    ++written_;
  }

  void commit() override {
    if (written_ != frames_ + 1) {
      throw Error(output_.target() + ": " + std::to_string(written_) + " frames written of " +
                  std::to_string(frames_ + 1) + "; not written");
    }
    Animation animation;
    if (frames_ > 0) frameAccessors(animation);
    poseChannels(animation);
    // The morph targets' accessors and buffer views follow every other, two of each per target:
    // written as text (targetsJson), a JSON tree of them would cost kilobytes a frame and body.
    const std::size_t firstAccessor = doc_["accessors"].size(), firstView = doc_["bufferViews"].size();
    std::vector<std::string> targetText(bodies_.size());
    std::string accessorText, viewText;
    targetsJson(firstAccessor, firstView, targetText, accessorText, viewText);
    if (frames_ > 0) {
      doc_["accessors"].push_back("@targets' accessors@");
      doc_["bufferViews"].push_back("@targets' buffer views@");
    }
    bodyNodes(animation);
    stillNodes();
    if (!animation.samplers.empty()) {
      doc_["animations"] = json::array(
          {{{"name", "springy"}, {"samplers", animation.samplers}, {"channels", animation.channels}}});
    }
    doc_["buffers"] = json::array({{{"byteLength", spill_.size()}}});
    // Pad the binary chunk to 4 bytes, the JSON chunk with spaces.
    const uint8_t zeros[4] = {0, 0, 0, 0};
    if (spill_.size() % 4) spill_.write(zeros, 4 - spill_.size() % 4);
    std::string text = doc_.dump();
    if (frames_ > 0) {
      std::string names;
      for (long k = 1; k <= frames_; ++k) names += (k > 1 ? ",\"frame " : "\"frame ") + std::to_string(k) + "\"";
      splice(text, "\"@targets' accessors@\"", accessorText);
      splice(text, "\"@targets' buffer views@\"", viewText);
      for (std::size_t i = 0; i < bodies_.size(); ++i) splice(text, "\"@targets " + std::to_string(i) + "@\"", targetText[i]);
      while (text.find("\"@names@\"") != std::string::npos) splice(text, "\"@names@\"", "[" + names + "]");
    }
    text.append((4 - text.size() % 4) % 4, ' ');
    writeGlb(text);
    output_.commit();
  }

  std::string written() const override { return output_.target(); }

 private:
  struct Target {
    uint64_t position = 0, normal = 0;  // offsets in the binary chunk
    std::array<float, 3> lo{}, hi{};    // the positions' range
  };
  struct Primitive {
    int indices = -1, material = -1, position = -1, normal = -1;
    std::vector<Target> targets;  // frames 1, 2, ...
  };

  // The morph targets as JSON text: per body the primitive's "targets" array, and the accessors
  // and buffer views they name (comma-separated, to follow the others'), numbered from `firstAccessor`
  // and `firstView`.
  void targetsJson(std::size_t firstAccessor, std::size_t firstView, std::vector<std::string>& targets,
                   std::string& accessors, std::string& views) const {
    std::size_t a = firstAccessor, v = firstView;
    char item[320];
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const std::size_t n = bodies_[i].vertexCount();
      targets[i] = "[";
      for (const Target& t : primitives_[i].targets) {
        std::snprintf(item, sizeof item, "%s{\"POSITION\":%zu,\"NORMAL\":%zu}", targets[i].size() > 1 ? "," : "", a,
                      a + 1);
        targets[i] += item;
        std::snprintf(item, sizeof item,
                      ",{\"bufferView\":%zu,\"componentType\":%d,\"count\":%zu,\"type\":\"VEC3\","
                      "\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]}"
                      ",{\"bufferView\":%zu,\"componentType\":%d,\"count\":%zu,\"type\":\"VEC3\"}",
                      v, kFloat, n, t.lo[0], t.lo[1], t.lo[2], t.hi[0], t.hi[1], t.hi[2], v + 1, kFloat, n);
        accessors += item;
        std::snprintf(item, sizeof item,
                      ",{\"buffer\":0,\"byteOffset\":%llu,\"byteLength\":%zu,\"target\":%d}"
                      ",{\"buffer\":0,\"byteOffset\":%llu,\"byteLength\":%zu,\"target\":%d}",
                      static_cast<unsigned long long>(t.position), 12 * n, kArrayBuffer,
                      static_cast<unsigned long long>(t.normal), 12 * n, kArrayBuffer);
        views += item;
        a += 2, v += 2;
      }
      targets[i] += "]";
    }
    // Each list follows the last fixed item: drop the leading comma where it is the first.
    if (firstAccessor == 0 && !accessors.empty()) accessors.erase(0, 1);
    if (firstView == 0 && !views.empty()) views.erase(0, 1);
  }
  // Replaces the placeholder `mark` (with the comma before it when `text` is a list's rest) in the
  // dumped JSON by `text`.
  static void splice(std::string& dumped, const std::string& mark, const std::string& text) {
    std::size_t at = dumped.find(mark);
    std::size_t length = mark.size();
    if (at == std::string::npos) throw Error("glTF export: placeholder " + mark + " lost");
    if (!text.empty() && text[0] == ',' && at > 0 && dumped[at - 1] == ',') --at, ++length;  // "...,@x@" -> "...,{..}"
    dumped.replace(at, length, text);
  }

  // The animation: its samplers and channels, the frames' times and the weights the bodies share.
  struct Animation {
    int times = -1, weights = -1;
    json samplers = json::array(), channels = json::array();
    void add(int node, const char* path, int input, int output) {
      channels.push_back({{"sampler", samplers.size()}, {"target", {{"node", node}, {"path", path}}}});
      samplers.push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
    }
  };
  // The frames' times and, shared by every body, the weights (frame k: target k - 1 at 1, all
  // others 0).
  void frameAccessors(Animation& animation) {
    const auto targets = static_cast<uint32_t>(frames_);
    std::vector<float> t(static_cast<std::size_t>(frames_ + 1));
    for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<float>(static_cast<double>(k) * frameTime_);
    animation.times = accessor(bufferView(spill_.write(t), 4 * t.size(), -1), 0, t.size(), "SCALAR", nullptr);
    doc_["accessors"][static_cast<std::size_t>(animation.times)]["min"] = {t.front()};
    doc_["accessors"][static_cast<std::size_t>(animation.times)]["max"] = {t.back()};
    std::vector<uint32_t> where(targets);
    for (uint32_t k = 1; k <= targets; ++k) where[k - 1] = k * targets + k - 1;
    const std::vector<float> ones(targets, 1.0f);
    const int whereView = bufferView(spill_.write(where), 4 * where.size(), -1);
    const int onesView = bufferView(spill_.write(ones), 4 * ones.size(), -1);
    json a = {{"componentType", kFloat},
              {"count", static_cast<uint64_t>(frames_ + 1) * targets},
              {"type", "SCALAR"},
              {"sparse",
               {{"count", targets},
                {"indices", {{"bufferView", whereView}, {"componentType", kUnsignedInt}}},
                {"values", {{"bufferView", onesView}}}}}};
    animation.weights = static_cast<int>(doc_["accessors"].size());
    doc_["accessors"].push_back(std::move(a));
  }
  // Each moving collider's pose at each frame (at the frame's simulated time, where the bodies
  // are): its node's translation and, where it turns, rotation, keyed at the frames' times; the
  // first frame's also as the node's own (a viewer that does not play shows the first frame).
  void poseChannels(Animation& animation) {
    for (const Moving& m : moving_) {
      std::vector<float> translation, rotation;
      posesAt(m.motion, times_, translation, rotation);
      json& node = stills_[m.still].second;
      node["translation"] = {translation[0], translation[1], translation[2]};
      const bool turns = m.motion.spin != 0.0;
      if (turns) node["rotation"] = {rotation[0], rotation[1], rotation[2], rotation[3]};
      if (animation.times < 0) continue;
      const int index = static_cast<int>(bodies_.size() + m.still);
      animation.add(index, "translation", animation.times, poseAccessor(translation, "VEC3"));
      if (turns) animation.add(index, "rotation", animation.times, poseAccessor(rotation, "VEC4"));
    }
  }
  int poseAccessor(const std::vector<float>& values, const char* type) {
    const int view = bufferView(spill_.write(values), 4 * values.size(), -1);
    return accessor(view, 0, times_.size(), type, nullptr);
  }
  // A node per body: its mesh, its morph targets (placeholders, spliced in at the end) and their
  // weights' channel.
  void bodyNodes(Animation& animation) {
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const Primitive& p = primitives_[i];
      json primitive = {{"attributes", {{"POSITION", p.position}, {"NORMAL", p.normal}}},
                        {"indices", p.indices},
                        {"material", p.material},
                        {"mode", 4}};
      json mesh = {{"name", bodies_[i].name}, {"primitives", json::array({primitive})}};
      if (frames_ > 0) {
        mesh["primitives"][0]["targets"] = "@targets " + std::to_string(i) + "@";
        mesh["weights"] = std::vector<float>(static_cast<std::size_t>(frames_), 0.0f);
        mesh["extras"] = {{"targetNames", "@names@"}};
        animation.add(static_cast<int>(doc_["nodes"].size()), "weights", animation.times, animation.weights);
      }
      addNode(bodies_[i].name, std::move(mesh), {});
    }
  }
  void stillNodes() {
    for (auto& [mesh, node] : stills_) {
      const std::string name = mesh["name"];  // before the move: arguments have no order
      addNode(name, std::move(mesh), std::move(node));
    }
  }
  // The GLB's header, its JSON chunk (`text`, padded) and its binary chunk (the spill file).
  void writeGlb(const std::string& text) {
    const uint64_t total = 12 + 8 + text.size() + 8 + spill_.size();
    if (total > UINT32_MAX) {
      throw Error(output_.target() + ": the run is " + std::to_string(total >> 20) +
                  " MiB as glTF, over GLB's 4 GiB; export fewer frames (--fps) or a shorter run, or use .pc2 or .pvd");
    }
    auto u32 = [](uint64_t v) {
      const uint32_t x = static_cast<uint32_t>(v);
      std::array<uint8_t, 4> b{};
      std::memcpy(b.data(), &x, 4);
      return b;
    };
    std::vector<uint8_t> head;
    auto put = [&](const std::array<uint8_t, 4>& b) { head.insert(head.end(), b.begin(), b.end()); };
    put({'g', 'l', 'T', 'F'});
    put(u32(2));
    put(u32(total));
    put(u32(text.size()));
    put({'J', 'S', 'O', 'N'});
    output_.write(head);
    output_.write(text);
    head.clear();
    put(u32(spill_.size()));
    put({'B', 'I', 'N', 0});
    output_.write(head);
    spill_.copyTo(output_);
  }

  int bufferView(uint64_t offset, uint64_t length, int target) {
    json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}};
    if (target > 0) v["target"] = target;
    doc_["bufferViews"].push_back(std::move(v));
    return static_cast<int>(doc_["bufferViews"].size()) - 1;
  }
  int accessor(int view, uint64_t offset, std::size_t count, const char* type, const Floats* range) {
    json a = {{"bufferView", view}, {"componentType", kFloat}, {"count", count}, {"type", type}};
    if (offset) a["byteOffset"] = offset;
    if (range) a["min"] = vec(range->lo), a["max"] = vec(range->hi);
    doc_["accessors"].push_back(std::move(a));
    return static_cast<int>(doc_["accessors"].size()) - 1;
  }
  int indexAccessor(const std::vector<uint32_t>& indices) {
    const int view = bufferView(spill_.write(indices), 4 * indices.size(), kElementArrayBuffer);
    json a = {{"bufferView", view}, {"componentType", kUnsignedInt}, {"count", indices.size()}, {"type", "SCALAR"}};
    doc_["accessors"].push_back(std::move(a));
    return static_cast<int>(doc_["accessors"].size()) - 1;
  }
  int material(const std::string& name, const Material& m, bool doubleSided) {
    const double roughness = std::sqrt(2.0 / (std::max(m.shininess, 0.0) + 2.0));  // Phong exponent to roughness
    const Vec3 c = linearColor(m.color);
    json j = {{"name", name},
              {"pbrMetallicRoughness",
               {{"baseColorFactor", {c.x, c.y, c.z, m.alpha}},
                {"metallicFactor", 0.0},
                {"roughnessFactor", roughness}}}};
    if (m.alpha < 1.0) j["alphaMode"] = "BLEND";
    if (doubleSided) j["doubleSided"] = true;
    doc_["materials"].push_back(std::move(j));
    return static_cast<int>(doc_["materials"].size()) - 1;
  }
  // A node of the scene with `mesh` and the node's other properties `node` (its placement), if any.
  void addNode(const std::string& name, json mesh, json node) {
    const int index = static_cast<int>(doc_["meshes"].size());
    doc_["meshes"].push_back(std::move(mesh));
    doc_["scenes"][0]["nodes"].push_back(doc_["nodes"].size());
    if (node.is_null()) node = json::object();
    node["name"] = name, node["mesh"] = index;
    doc_["nodes"].push_back(std::move(node));
  }
  // A still mesh (a collider): positions and indices now, its node at commit (after the bodies').
  void addStill(const std::string& name, const std::vector<double>& xyz, const std::vector<uint32_t>& indices,
                const Material& look) {
    Floats p;
    p.fill(xyz, nullptr);
    const int view = bufferView(spill_.write(p.values), 4 * p.values.size(), kArrayBuffer);
    const int position = accessor(view, 0, p.values.size() / 3, "VEC3", &p);
    const int index = indexAccessor(indices);
    json primitive = {{"attributes", {{"POSITION", position}}},
                      {"indices", index},
                      {"material", material(name, look, true)},
                      {"mode", 4}};
    stills_.emplace_back(json{{"name", name}, {"primitives", json::array({primitive})}}, json());
  }
  // The visible colliders and the props that move (colliderMeshes): a moving one is placed by
  // its node (poseChannels), its mesh as it is at rest.
  void addColliders(const SceneDesc& scene, const World& world) {
    for (const ColliderMesh& m : colliderMeshes(scene, world)) {
      if (m.moves()) moving_.push_back({stills_.size(), m.motion});
      addStill(m.name, m.xyz, m.indices, m.look);
    }
  }

  AtomicFile output_;
  SpillFile spill_;
  long frames_;
  double frameTime_;
  std::vector<ExportBody> bodies_;
  std::vector<Primitive> primitives_;
  std::vector<std::pair<std::vector<double>, std::vector<double>>> base_;  // per body: the first frame
  // A collider's mesh and its node's placement (null for one that stands still), added at commit
  // after the bodies' nodes.
  std::vector<std::pair<json, json>> stills_;
  struct Moving {
    std::size_t still;  // in stills_
    Movement motion;
  };
  std::vector<Moving> moving_;
  std::vector<double> times_;  // each frame's simulated time, when something moves
  json doc_;
  Floats position_, normal_;
  std::vector<double> xyz_, normals_;
  long written_ = 0;
};

}  // namespace

std::unique_ptr<MotionExport> openGltf(const std::string& path, const SceneDesc& scene, const World& world,
                                       long frames, double frameTime, const std::vector<std::string>& inputs) {
  return std::make_unique<GltfExport>(path, scene, world, frames, frameTime, inputs);
}

}  // namespace springy

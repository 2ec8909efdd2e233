// springy app: the simulated motion written out for other programs (`springy export`, `check
// --export`): every output frame of every body, as the mesh a viewer sees (the user's own mesh
// where a proxy simulates it), in one of three formats chosen by the output's extension:
//   .pc2  Blender's point cache (the Mesh Cache modifier reads it) and a .obj (+ .mtl) beside it
//         with the bodies at the first frame, one object whose vertices are the cache's points;
//         each collider or prop that moves an object of its own with its own cache (FILE.collider0.pc2)
//   .glb  glTF 2.0 binary: a mesh per body with its colour, its motion as one morph target per
//         frame and an animation of their weights; the visible colliders as meshes, each that
//         moves (and each prop that moves) a node whose animation places it at every frame
//   .pvd  ParaView's time series: a folder of .vtu files, one per body and frame, with per-vertex
//         velocity, strain, contact, pinned (and mass) and the body's volume as field data; each
//         collider or prop that moves a series of its own (FILE/collider0_NNNNNN.vtu)
// Every format streams: a frame is written when it is simulated, so memory does not grow with
// the run's length. Every output appears complete or not at all (AtomicFile; a folder is built
// under a temporary name and renamed), and the same run writes the same bytes on any thread count.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "render/mesh_builders.h"
#include "scene/scene.h"
#include "sim/monitor.h"

namespace springy {

enum class ExportFormat { PointCache, Gltf, VtkSeries };

// The format for an output's extension (case-insensitive). Throws springy::Error naming `option`
// and the file for any other, saying which extensions work.
ExportFormat exportFormatOf(const std::string& path, const std::string& option);
// The extension each format is written with (".pc2", ".glb", ".pvd").
const char* exportExtension(ExportFormat format);

// Whether the export at `path` (its format by extension) is one that springy wrote: a .glb whose
// asset names springy as its generator, a .pc2 beside a .obj that springy wrote, a .pvd beside a
// folder with springy's marker. For a name springy chose itself (-o DIR: DIR/SCENE.EXT), which
// may replace only springy's own file.
bool exportWrittenBySpringy(const std::string& path);

// One exported body: the drawn mesh's topology and how its vertices follow the model.
struct ExportBody {
  std::string name;
  uint32_t body = 0;                   // in the model
  std::vector<Triangle> triangles;     // the drawn mesh's, its own vertex indices
  std::vector<uint32_t> modelVertex;   // per drawn vertex: the model vertex it is (empty when embedded)
  Embedding binding;                   // per drawn vertex: its proxy triangle (corners: model vertices)
  Material look;
  std::size_t vertexCount() const { return binding.empty() ? modelVertex.size() : binding.size(); }
  bool embedded() const { return !binding.empty(); }
};

// The bodies of a world as exported: vertex k of a body drawn with its simulated mesh is the
// mesh's vertex k (the numbering of messages and pins), not the model's spatial order.
std::vector<ExportBody> exportBodies(const SceneDesc& scene, const World& world);

// A collider or prop of the scene as exported: x, y, z per vertex where it is at rest, three
// indices per triangle, and its motion (sim/motion.h; none for one that stands still): at time t
// its vertices are where motion.pose(t) takes them, as the renderer draws it (app/scene_view.cpp).
struct ColliderMesh {
  std::string name;  // "collider K", "plane K", "prop K"
  std::vector<double> xyz;
  std::vector<uint32_t> indices;
  Material look;
  Movement motion{};
  bool moves() const { return motion.moves(); }
  // Its vertices at time t (x, y, z per vertex).
  void placed(double t, std::vector<double>& out) const;
  // Its name as one word, for a file or an object ("collider0").
  std::string word() const;
};
// The visible colliders: triangle meshes as they are, a plane as a square around the bodies and
// the triangle colliders (its drawn half-size, at most twice their extent: a viewer frames the
// whole scene, and a 200 m ground would make the bodies specks); then the props that move (a bar
// carrying pins), as the renderer draws them. A prop that stands still is not exported.
std::vector<ColliderMesh> colliderMeshes(const SceneDesc& scene, const World& world);
// Those of them that move.
std::vector<ColliderMesh> movingMeshes(const SceneDesc& scene, const World& world);

// A prop's mesh, as the renderer draws it and an export writes it.
render::MeshData propMesh(const PropDesc& prop);

// A pose (x = R (p - c) + c + d) as a node's translation and rotation, glTF's and three.js's
// x = R p + t: t = c + d - R c and R as a unit quaternion (x, y, z, w).
struct NodePose {
  Vec3 translation;
  std::array<double, 4> rotation{0, 0, 0, 1};
};
NodePose nodePose(const Pose& pose);
// A motion's poses at `times` (nodePose) as 32-bit floats: the translations (x, y, z each) and the
// rotations (x, y, z, w each), each quaternion the one of its two (q and -q) nearer the one
// before, so that a viewer interpolating between keys turns the short way.
void posesAt(const Movement& motion, const std::vector<double>& times, std::vector<float>& translations,
             std::vector<float>& rotations);

// A scene colour (sRGB, as springy's renderer reads it) as the linear values glTF's base colour
// and Blender's material colour mean (IEC 61966-2-1's transfer function).
Vec3 linearColor(const Vec3& srgb);

// The drawn positions of a body in `world` (x, y, z per drawn vertex).
void drawnPositions(const ExportBody& body, const World& world, std::vector<double>& xyz);

// Per-vertex fields of a body's drawn mesh in `world`. An embedded vertex takes them from its
// proxy triangle: its velocity the corners' by the barycentric weights, its strain their largest,
// touching if a corner touches, pinned if all three are.
struct VertexFields {
  std::vector<double> velocity;   // x, y, z per vertex [m/s]
  std::vector<float> strain;      // the largest |l - l0| / l0 of the struts at the vertex
  std::vector<uint8_t> contact;   // 1: touching a collider or a body (World::touching)
  std::vector<uint8_t> pinned;    // 1: held in place
};
void vertexFields(const ExportBody& body, const World& world, VertexFields& out);

// A writer of one run. frame() is called for the first instant and then after each output
// frame; commit() makes the output appear (the destructor without commit() removes every
// temporary file, so a failure or a signal leaves nothing behind).
class MotionExport {
 public:
  virtual ~MotionExport() = default;
  virtual void frame(const World& world, const Monitor& monitor) = 0;
  virtual void commit() = 0;
  // What commit() wrote, for the closing message ("run.pc2 and run.obj").
  virtual std::string written() const = 0;
};

// Opens the writer for `path` (its format by extension) for a run of `frames` output frames after
// the first instant, frame interval `frameTime`. Checks at once that the output can be written
// (a directory that does not exist, a folder of the series that springy did not make, an input
// named as output): throws springy::Error before any simulation. `inputs`: files never written over.
std::unique_ptr<MotionExport> openExport(const std::string& path, const SceneDesc& scene, const World& world,
                                         long frames, double frameTime, const std::vector<std::string>& inputs);

// The writers (app/export_*.cpp).
std::unique_ptr<MotionExport> openPointCache(const std::string& path, const SceneDesc& scene, const World& world,
                                             long frames, double frameTime, const std::vector<std::string>& inputs);
std::unique_ptr<MotionExport> openGltf(const std::string& path, const SceneDesc& scene, const World& world,
                                       long frames, double frameTime, const std::vector<std::string>& inputs);
// The report's 3D replay (app/export_replay.cpp): a script for a page, not a format of `export`.
std::unique_ptr<MotionExport> openReplay(const std::string& path, const SceneDesc& scene, const World& world,
                                         long frames, double frameTime, const std::vector<std::string>& inputs);
std::unique_ptr<MotionExport> openVtkSeries(const std::string& path, const SceneDesc& scene, const World& world,
                                            long frames, double frameTime, const std::vector<std::string>& inputs);

}  // namespace springy

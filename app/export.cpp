#include "app/export.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "app/atomic_file.h"
#include "sim/error.h"

namespace springy {

ExportFormat exportFormatOf(const std::string& path, const std::string& option) {
  const std::size_t slash = path.rfind('/');
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::size_t dot = base.rfind('.');
  std::string ext = dot == std::string::npos || dot == 0 ? std::string() : base.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".pc2") return ExportFormat::PointCache;
  if (ext == ".glb") return ExportFormat::Gltf;
  if (ext == ".pvd") return ExportFormat::VtkSeries;
  std::string why = ext.empty() ? "has no extension" : "'" + ext + "' is not a format springy writes";
  if (ext == ".usd" || ext == ".usda" || ext == ".usdc" || ext == ".usdz") {
    why += " (USD is not written: no USD reader is at hand to test it against; .glb carries the same motion)";
  } else if (ext == ".gltf") {
    why += " (glTF is written as one binary file: .glb)";
  } else if (ext == ".vtu" || ext == ".vtk") {
    why += " (a run is a time series: .pvd, with a folder of .vtu files beside it)";
  }
  throw Error(option + " " + path + ": " + why +
              "; give .pc2 (Blender's point cache, with a .obj beside it), .glb (glTF 2.0) or .pvd (ParaView's time "
              "series of .vtu files)");
}

const char* exportExtension(ExportFormat format) {
  switch (format) {
    case ExportFormat::PointCache: return ".pc2";
    case ExportFormat::Gltf: return ".glb";
    case ExportFormat::VtkSeries: return ".pvd";
  }
  return "";
}

bool exportWrittenBySpringy(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string beside = fs::path(path).replace_extension("").string();
  switch (exportFormatOf(path, "-o")) {
    case ExportFormat::Gltf: {
      const std::string head = firstBytes(path, 1 << 16);
      return head.rfind("glTF", 0) == 0 && head.find("\"generator\":\"springy") != std::string::npos;
    }
    case ExportFormat::PointCache:
      return firstBytes(path, 12) == std::string("POINTCACHE2\0", 12) &&
             firstBytes(beside + ".obj", 16) == "# springy export";
    case ExportFormat::VtkSeries:
      return firstBytes(path, 5) == "<?xml" && fs::exists(beside + "/.springy-series");
  }
  return false;
}

namespace {

// The triangle colliders that are drawn; `all` grows to hold every one (drawn or not).
void triangleMeshes(const SceneDesc& scene, std::vector<ColliderMesh>& out, Bounds& all) {
  for (std::size_t c = 0; c < scene.triangleColliders.size(); ++c) {
    const TriMesh& m = scene.triangleColliders[c].mesh;
    const Bounds bc = boundsOf(m.positions);
    all = {componentMin(all.lo, bc.lo), componentMax(all.hi, bc.hi)};
    if (c < scene.view.triangleColliders.size() && !scene.view.triangleColliders[c].visible) continue;
    std::vector<double> xyz;
    for (const Vec3& p : m.positions) xyz.insert(xyz.end(), {p.x, p.y, p.z});
    std::vector<uint32_t> indices;
    for (const Triangle& t : m.triangles) indices.insert(indices.end(), t.begin(), t.end());
    const Material look = c < scene.view.triangleColliders.size() ? scene.view.triangleColliders[c].material
                                                                  : Material{};
    out.push_back({"collider " + std::to_string(c), std::move(xyz), std::move(indices), look,
                   scene.triangleColliders[c].motion});
  }
}

// A plane as a square of half-size h about the point of it nearest to `centre`.
ColliderMesh planeMesh(const PlaneCollider& plane, const Vec3& centre, double h) {
  const Vec3 n = normalized(plane.normal);
  const Vec3 middle = centre - n * dot(centre - plane.point, n);
  // Two directions in the plane.
  const Vec3 helper = std::abs(n.y) < 0.9 ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
  const Vec3 a = normalized(cross(helper, n)), b = cross(n, a);
  ColliderMesh out;
  for (const auto& [s, t] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
    const Vec3 q = middle + a * (s * h) + b * (t * h);
    out.xyz.insert(out.xyz.end(), {q.x, q.y, q.z});
  }
  // Counter-clockwise seen from the normal's side.
  const bool ccw = dot(cross(a, b), n) > 0.0;
  out.indices = ccw ? std::vector<uint32_t>{0, 1, 2, 0, 2, 3} : std::vector<uint32_t>{0, 2, 1, 0, 3, 2};
  out.motion = plane.motion;
  return out;
}

glm::vec3 toGlm(const Vec3& v) { return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)}; }

}  // namespace

std::vector<ColliderMesh> colliderMeshes(const SceneDesc& scene, const World& world) {
  std::vector<ColliderMesh> out;
  Bounds all = boundsOf(world.positions());
  triangleMeshes(scene, out, all);
  const Vec3 centre = (all.lo + all.hi) * 0.5;
  const double reach = std::max(length(all.hi - all.lo), 1.0);
  for (std::size_t p = 0; p < scene.planes.size(); ++p) {
    const SurfaceLook look = p < scene.view.planes.size() ? scene.view.planes[p] : SurfaceLook{};
    if (!look.visible) continue;
    ColliderMesh& m = out.emplace_back(planeMesh(scene.planes[p], centre, std::min(look.extent, reach)));
    m.name = "plane " + std::to_string(p);
    m.look = look.material;
  }
  for (std::size_t p = 0; p < scene.view.props.size(); ++p) {
    const PropDesc& prop = scene.view.props[p];
    if (!prop.motion.moves()) continue;
    const render::MeshData mesh = propMesh(prop);
    out.push_back({"prop " + std::to_string(p), std::vector<double>(mesh.positions.begin(), mesh.positions.end()),
                   mesh.indices, prop.material, prop.motion});
  }
  return out;
}

std::vector<ColliderMesh> movingMeshes(const SceneDesc& scene, const World& world) {
  std::vector<ColliderMesh> out = colliderMeshes(scene, world);
  std::erase_if(out, [](const ColliderMesh& m) { return !m.moves(); });
  return out;
}

void ColliderMesh::placed(double t, std::vector<double>& out) const {
  const Pose pose = motion.pose(t);
  out.resize(xyz.size());
  for (std::size_t k = 0; k + 2 < xyz.size(); k += 3) {
    const Vec3 x = pose.apply({xyz[k], xyz[k + 1], xyz[k + 2]});
    out[k] = x.x, out[k + 1] = x.y, out[k + 2] = x.z;
  }
}

std::string ColliderMesh::word() const {
  std::string out = name;
  std::erase(out, ' ');
  return out;
}

render::MeshData propMesh(const PropDesc& prop) {
  return prop.shape == PropDesc::Shape::Box
             ? render::makeBox(toGlm(prop.center), toGlm(prop.size) * 0.5f)
             : render::makeCylinder(toGlm(prop.from), toGlm(prop.to), static_cast<float>(prop.radius));
}

NodePose nodePose(const Pose& pose) {
  NodePose out;
  out.translation = pose.apply({0.0, 0.0, 0.0});
  // The rotation's matrix m[row][column] (the pose holds its columns) as a quaternion (Shepperd's
  // method: the largest of w, x, y, z first, for accuracy), w >= 0.
  const Vec3 &c0 = pose.rx, &c1 = pose.ry, &c2 = pose.rz;
  const double trace = c0.x + c1.y + c2.z;
  double x, y, z, w;
  if (trace > 0.0) {
    const double s = 2.0 * std::sqrt(trace + 1.0);
    w = 0.25 * s, x = (c1.z - c2.y) / s, y = (c2.x - c0.z) / s, z = (c0.y - c1.x) / s;
  } else if (c0.x > c1.y && c0.x > c2.z) {
    const double s = 2.0 * std::sqrt(1.0 + c0.x - c1.y - c2.z);
    w = (c1.z - c2.y) / s, x = 0.25 * s, y = (c1.x + c0.y) / s, z = (c2.x + c0.z) / s;
  } else if (c1.y > c2.z) {
    const double s = 2.0 * std::sqrt(1.0 + c1.y - c0.x - c2.z);
    w = (c2.x - c0.z) / s, x = (c1.x + c0.y) / s, y = 0.25 * s, z = (c2.y + c1.z) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + c2.z - c0.x - c1.y);
    w = (c0.y - c1.x) / s, x = (c2.x + c0.z) / s, y = (c2.y + c1.z) / s, z = 0.25 * s;
  }
  const double n = (w < 0.0 ? -1.0 : 1.0) / std::sqrt(x * x + y * y + z * z + w * w);
  out.rotation = {x * n, y * n, z * n, w * n};
  return out;
}

void posesAt(const Movement& motion, const std::vector<double>& times, std::vector<float>& translations,
             std::vector<float>& rotations) {
  translations.clear(), rotations.clear();
  std::array<double, 4> last{0, 0, 0, 1};
  for (double t : times) {
    NodePose p = nodePose(motion.pose(t));
    double along = 0.0;
    for (int k = 0; k < 4; ++k) along += p.rotation[k] * last[k];
    if (along < 0.0) {
      for (double& q : p.rotation) q = -q;
    }
    last = p.rotation;
    for (int k = 0; k < 3; ++k) translations.push_back(static_cast<float>(p.translation[k]));
    for (double q : p.rotation) rotations.push_back(static_cast<float>(q));
  }
}

std::vector<ExportBody> exportBodies(const SceneDesc& scene, const World& world) {
  const Model& model = world.model();
  std::vector<ExportBody> bodies;
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    const BodyInfo& info = model.bodies[b];
    const BodyDesc& desc = scene.bodies[b];
    ExportBody& out = bodies.emplace_back();
    out.name = info.name;
    out.body = b;
    out.look = b < scene.view.bodies.size() ? scene.view.bodies[b] : Material{};
    if (!desc.drawBinding.empty()) {
      // The user's own mesh over the proxy: its vertices, bound to the proxy's (mesh) vertices.
      out.binding = desc.drawBinding;
      for (Triangle& t : out.binding.corners) {
        for (uint32_t& v : t) v = info.modelVertex[v];
      }
      out.triangles = desc.drawMesh.triangles;
      continue;
    }
    // The simulated mesh in the mesh's own order: drawn vertex k is mesh vertex k.
    out.modelVertex = info.modelVertex;
    std::vector<uint32_t> meshOf(info.vertexCount);
    for (uint32_t k = 0; k < info.modelVertex.size(); ++k) meshOf[info.modelVertex[k] - info.firstVertex] = k;
    out.triangles.reserve(info.faceCount);
    for (uint32_t f = info.firstFace; f < info.firstFace + info.faceCount; ++f) {
      Triangle t = model.faces[f];
      for (uint32_t& v : t) v = meshOf[v - info.firstVertex];
      out.triangles.push_back(t);
    }
  }
  return bodies;
}

Vec3 linearColor(const Vec3& srgb) {
  const auto channel = [](double c) {
    c = std::clamp(c, 0.0, 1.0);
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
  };
  return {channel(srgb.x), channel(srgb.y), channel(srgb.z)};
}

void drawnPositions(const ExportBody& body, const World& world, std::vector<double>& xyz) {
  const std::vector<Vec3>& x = world.positions();
  xyz.resize(3 * body.vertexCount());
  if (body.embedded()) {
    placeEmbedded(body.binding, &x[0].x, xyz.data());
    return;
  }
  for (std::size_t k = 0; k < body.modelVertex.size(); ++k) {
    const Vec3& p = x[body.modelVertex[k]];
    xyz[3 * k] = p.x, xyz[3 * k + 1] = p.y, xyz[3 * k + 2] = p.z;
  }
}

void vertexFields(const ExportBody& body, const World& world, VertexFields& out) {
  const Model& model = world.model();
  const BodyInfo& info = model.bodies[body.body];
  const std::vector<Vec3>& x = world.positions();
  const std::vector<Vec3>& v = world.velocities();
  // The largest strain at each of the body's (model) vertices.
  std::vector<float> strain(info.vertexCount, 0.0f);
  for (uint32_t s = info.firstStrut; s < info.firstStrut + info.strutCount; ++s) {
    const Strut& st = model.struts[s];
    if (!(st.restLength > 0.0)) continue;
    const float e = static_cast<float>(std::abs(length(x[st.j] - x[st.i]) - st.restLength) / st.restLength);
    float& a = strain[st.i - info.firstVertex];
    float& b = strain[st.j - info.firstVertex];
    a = std::max(a, e), b = std::max(b, e);
  }
  const auto pinned = [&](uint32_t i) -> uint8_t { return world.inverseMasses()[i] == 0.0 ? 1 : 0; };
  const std::size_t n = body.vertexCount();
  out.velocity.resize(3 * n);
  out.strain.resize(n);
  out.contact.resize(n);
  out.pinned.resize(n);
  if (!body.embedded()) {
    for (std::size_t k = 0; k < n; ++k) {
      const uint32_t i = body.modelVertex[k];
      out.velocity[3 * k] = v[i].x, out.velocity[3 * k + 1] = v[i].y, out.velocity[3 * k + 2] = v[i].z;
      out.strain[k] = strain[i - info.firstVertex];
      out.contact[k] = world.touching(i) ? 1 : 0;
      out.pinned[k] = pinned(i);
    }
    return;
  }
  for (std::size_t k = 0; k < n; ++k) {
    const Triangle& t = body.binding.corners[k];
    const double u = body.binding.coords[k][0], w = body.binding.coords[k][1];
    const Vec3 vel = v[t[0]] * (1.0 - u - w) + v[t[1]] * u + v[t[2]] * w;
    out.velocity[3 * k] = vel.x, out.velocity[3 * k + 1] = vel.y, out.velocity[3 * k + 2] = vel.z;
    float e = 0.0f;
    uint8_t touching = 0, held = 1;
    for (uint32_t i : t) {
      e = std::max(e, strain[i - info.firstVertex]);
      touching = touching || world.touching(i);
      held = held && pinned(i);
    }
    out.strain[k] = e;
    out.contact[k] = touching;
    out.pinned[k] = held;
  }
}

std::unique_ptr<MotionExport> openExport(const std::string& path, const SceneDesc& scene, const World& world,
                                         long frames, double frameTime, const std::vector<std::string>& inputs) {
  switch (exportFormatOf(path, "--export")) {
    case ExportFormat::PointCache: return openPointCache(path, scene, world, frames, frameTime, inputs);
    case ExportFormat::Gltf: return openGltf(path, scene, world, frames, frameTime, inputs);
    case ExportFormat::VtkSeries: return openVtkSeries(path, scene, world, frames, frameTime, inputs);
  }
  throw Error(path + ": no writer for this format");
}

}  // namespace springy

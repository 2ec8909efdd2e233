#include "app/scene_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <span>

#include "app/export.h"
#include "sim/error.h"

namespace springy {
namespace {

glm::vec3 toGlm(const Vec3& v) { return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)}; }

render::Material toMaterial(const Material& m) {
  render::Material r;
  r.colour = toGlm(m.color);
  r.alpha = static_cast<float>(m.alpha);
  r.shininess = static_cast<float>(m.shininess);
  r.flat = m.flat;
  return r;
}

// Euler angles (degrees, z then x then y, as the original Unity scenes) applied to +z.
Vec3 forwardFromAngles(const Vec3& degrees) {
  const double rx = degrees.x * kPi / 180, ry = degrees.y * kPi / 180;
  const Vec3 f{0.0, -std::sin(rx), std::cos(rx)};  // pitch about x (roll about z leaves +z alone)
  return {f.x * std::cos(ry) + f.z * std::sin(ry), f.y, -f.x * std::sin(ry) + f.z * std::cos(ry)};
}

}  // namespace

void checkCamera(const SceneDesc& scene) {
  const CameraDesc& c = scene.view.render.camera;
  if (c.position && c.target && *c.position == *c.target) {
    char at[128];
    std::snprintf(at, sizeof at, "[%g, %g, %g]", c.position->x, c.position->y, c.position->z);
    throw Error(scene.path + ": [render.camera] position and target are the same point " + at +
                ": the camera has no direction to look in; move one of them");
  }
}

render::RenderSettings renderSettingsOf(const SceneDesc& scene) {
  render::RenderSettings s;
  s.width = scene.view.render.width;
  s.height = scene.view.render.height;
  s.antiAlias = scene.view.render.antialias;
  s.shadows = scene.view.render.shadows;
  s.shadowMapSize = scene.view.render.shadowMapSize;
  return s;
}

namespace {

// The bounds the default camera frames: the bodies' and where they land, their shadows straight
// down onto each plane they are above (a body dropped onto the ground otherwise falls out of the
// picture).
Bounds landingBounds(const SceneDesc& scene, const World& world) {
  const Bounds bodies = boundsOf(world.positions());
  Bounds all = bodies;
  for (const PlaneCollider& p : scene.planes) {
    const Vec3 n = p.normal;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 x{corner & 1 ? bodies.hi.x : bodies.lo.x, corner & 2 ? bodies.hi.y : bodies.lo.y,
                   corner & 4 ? bodies.hi.z : bodies.lo.z};
      const double height = dot(x - p.point, n);
      if (!(height > 0.0) || !(height < 1e3 * length(bodies.size()) + 1.0)) continue;
      const Vec3 landing = x - n * height;
      all = {componentMin(all.lo, landing), componentMax(all.hi, landing)};
    }
  }
  return all;
}

}  // namespace

SceneView::SceneView(const SceneDesc& scene, const World& world, render::RenderSettings settings)
    : scene_(scene), renderer_(settings) {
  checkCamera(scene);
  integrator_ = std::string(integratorName(world.integrator()));
  Bounds all = landingBounds(scene, world);
  addBodies(world);
  addColliders(all);
  placeCamera(all);
}

void SceneView::addBodies(const World& world) {
  const SceneDesc& scene = scene_;
  const Model& model = world.model();
  // Topology once, body-local indices.
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    const BodyInfo& info = model.bodies[b];
    const BodyDesc& desc = scene.bodies[b];
    std::vector<uint32_t> indices;
    bodyVertexCounts_.push_back(info.vertexCount);
    drawBindings_.emplace_back();
    if (!desc.drawBinding.empty()) {
      // The user's own mesh over the proxy: its topology, its vertices placed from the proxy's.
      Embedding& binding = drawBindings_.back();
      binding = desc.drawBinding;
      for (Triangle& t : binding.corners) {
        for (uint32_t& v : t) v = info.modelVertex[v] - info.firstVertex;
      }
      for (const Triangle& t : desc.drawMesh.triangles) indices.insert(indices.end(), t.begin(), t.end());
      bodyMeshes_.push_back(renderer_.addDynamicMesh(static_cast<uint32_t>(desc.drawMesh.positions.size()), indices,
                                                     toMaterial(scene.view.bodies[b])));
      continue;
    }
    indices.reserve(static_cast<std::size_t>(info.faceCount) * 3);
    for (uint32_t f = info.firstFace; f < info.firstFace + info.faceCount; ++f) {
      for (uint32_t v : model.faces[f]) indices.push_back(v - info.firstVertex);
    }
    bodyMeshes_.push_back(renderer_.addDynamicMesh(info.vertexCount, indices, toMaterial(scene.view.bodies[b])));
  }
}

// The planes, triangle colliders and props; `all` grows to hold the triangle colliders.
void SceneView::addColliders(Bounds& all) {
  const SceneDesc& scene = scene_;
  for (std::size_t p = 0; p < scene.planes.size(); ++p) {
    const PlaneCollider& plane = scene.planes[p];
    const SurfaceLook& look = scene.view.planes[p];
    if (!look.visible) continue;
    const glm::vec3 c = toGlm(look.material.color);
    // Two tones of the plane's colour make the checker that shows depth.
    const render::MeshId id = renderer_.addGround(toGlm(plane.point), toGlm(plane.normal),
                                                  static_cast<float>(look.extent), c * 1.12f, c * 0.88f, 2.0f);
    if (plane.motion.moves()) movingPlanes_.push_back({id, p});
  }
  for (std::size_t c = 0; c < scene.triangleColliders.size(); ++c) {
    const TriMesh& m = scene.triangleColliders[c].mesh;
    const SurfaceLook& look = scene.view.triangleColliders[c];
    all = {componentMin(all.lo, boundsOf(m.positions).lo), componentMax(all.hi, boundsOf(m.positions).hi)};
    if (!look.visible) continue;
    std::vector<float> xyz;
    std::vector<uint32_t> indices;
    for (const Vec3& p : m.positions) {
      for (int k = 0; k < 3; ++k) xyz.push_back(static_cast<float>(p[k]));
    }
    for (const Triangle& tri : m.triangles) indices.insert(indices.end(), tri.begin(), tri.end());
    if (scene.triangleColliders[c].motion.moves()) {
      // Drawn where its motion has it at each frame, as given (a rigid plate, not a soft patch).
      movingMeshes_.push_back({renderer_.addDynamicMesh(m.positions.size(), indices, toMaterial(look.material), false), c});
    } else {
      renderer_.addStaticMesh(xyz, indices, toMaterial(look.material));
    }
  }
  for (const PropDesc& p : scene.view.props) {
    const render::MeshData mesh = propMesh(p);
    if (p.motion.moves()) {
      movingProps_.push_back({renderer_.addDynamicMesh(mesh.positions.size() / 3, mesh.indices, toMaterial(p.material), false),
                              static_cast<std::size_t>(&p - scene.view.props.data())});
      propRest_.push_back(mesh.positions);
    } else {
      renderer_.addStaticMesh(mesh, toMaterial(p.material));
    }
  }
}

// The camera (the scene's, or one that frames everything that moves or collides: `all`), the light
// and the sky.
void SceneView::placeCamera(const Bounds& all) {
  const RenderDesc& rd = scene_.view.render;
  render::Camera camera;
  if (rd.camera.position) {
    camera.position = toGlm(*rd.camera.position);
    camera.target = rd.camera.target ? toGlm(*rd.camera.target)
                    : toGlm(*rd.camera.position + forwardFromAngles(rd.camera.angles.value_or(Vec3{})));
    camera.fovYDeg = static_cast<float>(rd.camera.fov);
    camera.farPlane = 1000.0f;
    camera.nearPlane = 0.1f;
  } else {
    camera = render::frameBounds(toGlm(all.lo), toGlm(all.hi), renderer_.aspect(), static_cast<float>(rd.camera.fov));
  }
  renderer_.setCamera(camera);
  render::Light light;
  light.direction = toGlm(forwardFromAngles(rd.light.angles));
  light.colour = toGlm(rd.light.color) * 0.9f;
  light.ambient = glm::vec3(static_cast<float>(rd.light.ambient));
  renderer_.setLight(light);
  renderer_.setSky(toGlm(rd.skyTop), toGlm(rd.skyBottom));
}

void takeSnapshot(const World& world, FrameSnapshot& snapshot) {
  snapshot.time = world.time();
  snapshot.dt = world.dt();
  const Model& model = world.model();
  const std::vector<Vec3>& x = world.positions();
  std::size_t n = 0;
  for (const BodyInfo& info : model.bodies) n += info.vertexCount;
  snapshot.positions.resize(3 * n);
  snapshot.resting.resize(n);
  float* out = snapshot.positions.data();
  uint8_t* resting = snapshot.resting.data();
  for (const BodyInfo& info : model.bodies) {
    for (uint32_t i = 0; i < info.vertexCount; ++i) {
      const Vec3& p = x[info.firstVertex + i];
      *out++ = static_cast<float>(p.x);
      *out++ = static_cast<float>(p.y);
      *out++ = static_cast<float>(p.z);
      *resting++ = world.restsOnCollider(info.firstVertex + i) ? 1 : 0;
    }
  }
}

void SceneView::draw(const FrameSnapshot& snapshot) {
  std::size_t offset = 0;
  for (std::size_t b = 0; b < bodyMeshes_.size(); ++b) {
    const std::size_t n = 3 * static_cast<std::size_t>(bodyVertexCounts_[b]);
    const std::span<const float> body = std::span<const float>(snapshot.positions).subspan(offset, n);
    if (drawBindings_[b].empty()) {
      // A vertex resting on a collider keeps the drawn surface flat there: a smooth patch would
      // bulge through a thin wall that the flat mesh lies on.
      const std::span<const uint8_t> flat =
          snapshot.resting.empty() ? std::span<const uint8_t>()
                                   : std::span<const uint8_t>(snapshot.resting).subspan(offset / 3, n / 3);
      renderer_.updateDynamicMesh(bodyMeshes_[b], body, flat);
    } else {
      placed_.resize(3 * drawBindings_[b].size());
      placeEmbedded(drawBindings_[b], body.data(), placed_.data());
      renderer_.updateDynamicMesh(bodyMeshes_[b], placed_);
    }
    offset += n;
  }
  placeMovingColliders(snapshot.time);
  if (scene_.view.render.overlay) {
    char time[64], method[96];
    std::snprintf(time, sizeof time, "t = %.2f s", snapshot.time);
    std::snprintf(method, sizeof method, "%s, dt = %g ms%s", integrator_.c_str(), snapshot.dt * 1000.0, "");
    renderer_.setOverlayText({scene_.name, time, method});
  }
  renderer_.render();
}

void SceneView::placeMovingColliders(double t) {
  for (const Moving& m : movingPlanes_) {
    const PlaneCollider& plane = scene_.planes[m.index];
    const Pose pose = plane.motion.pose(t);
    const glm::mat3 rotation(toGlm(pose.rx), toGlm(pose.ry), toGlm(pose.rz));  // columns
    renderer_.placeGround(m.id, toGlm(pose.apply(plane.point)), rotation);
  }
  const auto place = [&](render::MeshId id, const Pose& pose, std::size_t count, auto&& point) {
    placed_.clear();
    for (std::size_t k = 0; k < count; ++k) {
      const Vec3 x = pose.apply(point(k));
      placed_.insert(placed_.end(), {static_cast<float>(x.x), static_cast<float>(x.y), static_cast<float>(x.z)});
    }
    renderer_.updateDynamicMesh(id, placed_);
  };
  for (const Moving& m : movingMeshes_) {
    const TriangleCollider& collider = scene_.triangleColliders[m.index];
    place(m.id, collider.motion.pose(t), collider.mesh.positions.size(),
          [&](std::size_t k) { return collider.mesh.positions[k]; });
  }
  for (std::size_t k = 0; k < movingProps_.size(); ++k) {
    const std::vector<float>& rest = propRest_[k];
    place(movingProps_[k].id, scene_.view.props[movingProps_[k].index].motion.pose(t), rest.size() / 3,
          [&](std::size_t i) { return Vec3{rest[3 * i], rest[3 * i + 1], rest[3 * i + 2]}; });
  }
}

void SceneView::draw(const World& world) {
  takeSnapshot(world, scratch_);
  draw(scratch_);
}

std::vector<double> sheetTimes(double duration) {
  std::vector<double> times;
  for (int i = 0; i < 8; ++i) times.push_back(duration * i / 7.0);
  return times;
}

render::ContactSheetOptions sheetOptions(std::size_t stills) {
  render::ContactSheetOptions sheet;
  sheet.columns = static_cast<int>(std::min<std::size_t>(4, stills));
  return sheet;
}

}  // namespace springy

#include "sim/intersections.h"

#include <array>

#include "sim/contact_bvh.h"

namespace springy {

bool segmentCrossesTriangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& point) {
  const Vec3 n = cross(b - a, c - a);
  const double dp = dot(p - a, n), dq = dot(q - a, n);
  if (!((dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0))) return false;
  point = p + (q - p) * (dp / (dp - dq));
  return dot(cross(b - a, point - a), n) >= 0.0 && dot(cross(c - b, point - b), n) >= 0.0 &&
         dot(cross(a - c, point - c), n) >= 0.0;
}

namespace {

bool trianglesCross(const Model& model, const std::vector<Vec3>& x, uint32_t f, uint32_t g, Vec3& point) {
  const Triangle &s = model.faces[f], &t = model.faces[g];
  for (int k = 0; k < 3; ++k) {
    const uint32_t i = s[static_cast<std::size_t>(k)], j = s[static_cast<std::size_t>((k + 1) % 3)];
    if (segmentCrossesTriangle(x[i], x[j], x[t[0]], x[t[1]], x[t[2]], point)) return true;
    const uint32_t u = t[static_cast<std::size_t>(k)], w = t[static_cast<std::size_t>((k + 1) % 3)];
    if (segmentCrossesTriangle(x[u], x[w], x[s[0]], x[s[1]], x[s[2]], point)) return true;
  }
  return false;
}

// Whether an edge of triangle (a0, a1, a2) passes through (b0, b1, b2) or one of the latter's
// through the former.
bool crosses(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b, Vec3& point) {
  for (std::size_t k = 0; k < 3; ++k) {
    if (segmentCrossesTriangle(a[k], a[(k + 1) % 3], b[0], b[1], b[2], point)) return true;
    if (segmentCrossesTriangle(b[k], b[(k + 1) % 3], a[0], a[1], a[2], point)) return true;
  }
  return false;
}

Box triangleBox(const std::array<Vec3, 3>& t) { return sweptBox({t[0], t[0]}, {t[1], t[1]}, {t[2], t[2]}, 0.0); }

}  // namespace

std::vector<ColliderCrossing> findColliderCrossings(const Model& model, const std::vector<Vec3>& x, double t,
                                                    std::size_t limit) {
  std::vector<ColliderCrossing> found;
  const auto& meshes = model.colliders.meshes;
  if (meshes.empty()) return found;
  const auto bodyFace = [&](uint32_t f) {
    const Triangle& tri = model.faces[f];
    return std::array<Vec3, 3>{x[tri[0]], x[tri[1]], x[tri[2]]};
  };
  // A body's tree is built only when its bounds meet a collider's.
  std::vector<Bvh> trees(model.bodies.size());
  std::vector<char> built(model.bodies.size(), 0);
  std::vector<Vec3> lo(model.bodies.size(), Vec3{1e300, 1e300, 1e300}), hi(model.bodies.size(), Vec3{-1e300, -1e300, -1e300});
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    const BodyInfo& info = model.bodies[b];
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      lo[b] = componentMin(lo[b], x[i]);
      hi[b] = componentMax(hi[b], x[i]);
    }
  }
  std::vector<Box> boxes;
  const auto treeOf = [&](uint32_t b) -> const Bvh& {
    if (!built[b]) {
      const BodyInfo& info = model.bodies[b];
      std::vector<Box> faces;
      for (uint32_t f = info.firstFace; f < info.firstFace + info.faceCount; ++f) faces.push_back(triangleBox(bodyFace(f)));
      trees[b].build(faces);
      built[b] = 1;
    }
    return trees[b];
  };
  std::vector<std::array<Vec3, 3>> posed;
  std::vector<PrimitivePair> pairs;
  for (uint32_t c = 0; c < meshes.size() && found.size() < limit; ++c) {
    const TriangleCollider& tc = meshes[c];
    const Pose pose = tc.motion.moves() ? tc.motion.pose(t) : Pose{};
    posed.clear();
    boxes.clear();
    Vec3 clo{1e300, 1e300, 1e300}, chi{-1e300, -1e300, -1e300};
    for (const Triangle& tri : tc.mesh.triangles) {
      std::array<Vec3, 3> p;
      for (std::size_t k = 0; k < 3; ++k) {
        p[k] = pose.apply(tc.mesh.positions[tri[k]]);
        clo = componentMin(clo, p[k]);
        chi = componentMax(chi, p[k]);
      }
      posed.push_back(p);
      boxes.push_back(triangleBox(p));
    }
    Bvh tree;
    bool treeBuilt = false;
    for (uint32_t b = 0; b < model.bodies.size() && found.size() < limit; ++b) {
      if (lo[b].x > chi.x || lo[b].y > chi.y || lo[b].z > chi.z || clo.x > hi[b].x || clo.y > hi[b].y ||
          clo.z > hi[b].z)
        continue;
      if (!treeBuilt) tree.build(boxes), treeBuilt = true;
      const uint32_t first = model.bodies[b].firstFace;
      pairs.clear();
      overlapPairs(treeOf(b), tree, pairs);
      for (const PrimitivePair& p : pairs) {
        if (found.size() >= limit) break;
        Vec3 point;
        if (crosses(bodyFace(first + p.a), posed[p.b], point)) found.push_back({b, first + p.a, c, p.b, point});
      }
    }
  }
  return found;
}

std::vector<Intersection> findIntersections(const Model& model, const std::vector<Vec3>& x, std::size_t limit) {
  std::vector<Intersection> found;
  const std::size_t bodies = model.bodies.size();
  std::vector<Bvh> trees(bodies);
  std::vector<Box> boxes;
  // A body's tree is built only when something is tested against it: its own faces (self
  // contact) or another body that takes part in contact. A lone body without self contact (the
  // common single-ball scene) needs none; for a 40962-vertex ball the tree was a fifth of the set-up.
  uint32_t inContact = 0;
  for (const BodyInfo& info : model.bodies) inContact += info.contact ? 1u : 0u;
  for (uint32_t b = 0; b < bodies; ++b) {
    const BodyInfo& info = model.bodies[b];
    if (!info.selfContact && !(info.contact && inContact > 1)) continue;
    boxes.clear();
    for (uint32_t f = info.firstFace; f < info.firstFace + info.faceCount; ++f) {
      const Triangle& t = model.faces[f];
      boxes.push_back(sweptBox({x[t[0]], x[t[0]]}, {x[t[1]], x[t[1]]}, {x[t[2]], x[t[2]]}, 0.0));
    }
    trees[b].build(boxes);
  }
  std::vector<PrimitivePair> pairs;
  const auto test = [&](uint32_t a, uint32_t b) {
    const uint32_t fa = model.bodies[a].firstFace, fb = model.bodies[b].firstFace;
    for (const PrimitivePair& p : pairs) {
      Vec3 point;
      if (found.size() >= limit) return;
      if (trianglesCross(model, x, fa + p.a, fb + p.b, point)) found.push_back({a, fa + p.a, b, fb + p.b, point});
    }
  };
  for (uint32_t a = 0; a < bodies && found.size() < limit; ++a) {
    const BodyInfo& A = model.bodies[a];
    if (A.selfContact) {
      pairs.clear();
      selfOverlapPairs(
          trees[a],
          [&](uint32_t f, uint32_t g) {
            const Triangle &s = model.faces[A.firstFace + f], &t = model.faces[A.firstFace + g];
            for (uint32_t i : s) {
              if (i == t[0] || i == t[1] || i == t[2]) return true;
            }
            return false;
          },
          pairs);
      test(a, a);
    }
    if (!A.contact) continue;
    for (uint32_t b = a + 1; b < bodies && found.size() < limit; ++b) {
      if (!model.bodies[b].contact) continue;
      pairs.clear();
      overlapPairs(trees[a], trees[b], pairs);
      test(a, b);
    }
  }
  return found;
}

}  // namespace springy

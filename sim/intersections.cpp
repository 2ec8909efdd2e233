#include "sim/intersections.h"

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

}  // namespace

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

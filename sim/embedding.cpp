#include "sim/embedding.h"

#include <algorithm>
#include <limits>

#include "sim/colliders.h"

namespace springy {
namespace {

// The point of triangle (a, b, c) nearest to p (Ericson, Real-Time Collision Detection, 5.1.5:
// the Voronoi region of p decides between a corner, an edge and the face).
Vec3 closestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

double boxDistanceSquared(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  double sum = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double d = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0.0);
    sum += d * d;
  }
  return sum;
}

}  // namespace

Embedding bindToSurface(const TriMesh& surface, const std::vector<Vec3>& points) {
  // The colliders' bounding volume hierarchy over the surface's triangles serves the search.
  TriangleCollider tree;
  tree.mesh = surface;
  tree.buildBvh();
  const std::vector<Vec3>& x = surface.positions;

  Embedding e;
  e.corners.reserve(points.size());
  e.coords.reserve(points.size());
  std::vector<uint32_t> stack;
  for (const Vec3& p : points) {
    double best = std::numeric_limits<double>::infinity();
    uint32_t bestFace = 0;
    stack.assign(1, 0);
    while (!stack.empty()) {
      const uint32_t n = stack.back();
      stack.pop_back();
      const TriangleCollider::Node& node = tree.nodes[n];
      if (boxDistanceSquared(p, node.lo, node.hi) > best) continue;
      if (node.count > 0) {
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
          const uint32_t f = tree.order[k];
          const Triangle& t = surface.triangles[f];
          const double d = lengthSquared(p - closestOnTriangle(p, x[t[0]], x[t[1]], x[t[2]]));
          if (d < best || (d == best && f < bestFace)) {
            best = d;
            bestFace = f;
          }
        }
      } else {
        stack.push_back(node.second);
        stack.push_back(n + 1);
      }
    }
    // Coordinates in the face's frame: p - p0 = u e1 + v e2 + h n, n the unit normal. The
    // tangential part solves the 2x2 normal equations of (e1, e2); h is the distance along n.
    const Triangle& t = surface.triangles[bestFace];
    const Vec3 e1 = x[t[1]] - x[t[0]], e2 = x[t[2]] - x[t[0]], r = p - x[t[0]];
    const Vec3 normal = normalized(cross(e1, e2));
    const double a11 = dot(e1, e1), a12 = dot(e1, e2), a22 = dot(e2, e2);
    const double b1 = dot(r, e1), b2 = dot(r, e2);
    const double det = a11 * a22 - a12 * a12;
    const double u = (b1 * a22 - b2 * a12) / det, v = (a11 * b2 - a12 * b1) / det;
    e.corners.push_back(t);
    e.coords.push_back({u, v, dot(r, normal)});
  }
  return e;
}

}  // namespace springy

#include "sim/colliders.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace springy {
namespace {

// Segment p -> q against triangle (a, b, c), two-sided. Returns the fraction along the segment
// of the crossing, or a negative number. Crossing = the segment's end points lie on opposite
// sides of (or the end point on) the triangle's plane and the crossing point is inside.
double segmentTriangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& normal) {
  const Vec3 n = cross(b - a, c - a);
  const double dp = dot(p - a, n), dq = dot(q - a, n);
  if ((dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) || dp == dq) return -1.0;
  if (dp == 0.0) return -1.0;  // starts on the surface: moving away or along it, not a hit
  const double s = dp / (dp - dq);
  const Vec3 x = p + (q - p) * s;
  // Inside test with edge functions (same sign as n for all three edges). Two triangles that
  // share an edge compute that edge's function from different corners, so round-off can put
  // a crossing exactly on the edge just outside both: a small tolerance (relative to |n|^2,
  // i.e. 1e-9 of the triangle's size) closes the crack; a hit found in both is harmless.
  const double tolerance = -1e-9 * dot(n, n);
  if (dot(cross(b - a, x - a), n) < tolerance) return -1.0;
  if (dot(cross(c - b, x - b), n) < tolerance) return -1.0;
  if (dot(cross(a - c, x - c), n) < tolerance) return -1.0;
  normal = normalized(dp > 0.0 ? n : -n);
  return s;
}

bool boxOverlap(const Vec3& lo, const Vec3& hi, const Vec3& blo, const Vec3& bhi) {
  return lo.x <= bhi.x && hi.x >= blo.x && lo.y <= bhi.y && hi.y >= blo.y && lo.z <= bhi.z && hi.z >= blo.z;
}

}  // namespace

void TriangleCollider::buildBvh() {
  const std::size_t n = mesh.triangles.size();
  order.resize(n);
  std::vector<Vec3> centroid(n), lo(n), hi(n);
  for (std::size_t t = 0; t < n; ++t) {
    order[t] = static_cast<uint32_t>(t);
    const Triangle& tri = mesh.triangles[t];
    const Vec3 &a = mesh.positions[tri[0]], &b = mesh.positions[tri[1]], &c = mesh.positions[tri[2]];
    lo[t] = componentMin(a, componentMin(b, c));
    hi[t] = componentMax(a, componentMax(b, c));
    centroid[t] = (a + b + c) / 3.0;
  }
  nodes.clear();
  // Recursive median split on the longest axis of the centroid bounds; ties broken by index,
  // so the tree is deterministic.
  auto build = [&](auto&& self, uint32_t first, uint32_t count) -> void {
    const std::size_t index = nodes.size();
    nodes.push_back({});
    Vec3 nlo = lo[order[first]], nhi = hi[order[first]], clo = centroid[order[first]], chi = clo;
    for (uint32_t k = first; k < first + count; ++k) {
      nlo = componentMin(nlo, lo[order[k]]);
      nhi = componentMax(nhi, hi[order[k]]);
      clo = componentMin(clo, centroid[order[k]]);
      chi = componentMax(chi, centroid[order[k]]);
    }
    nodes[index].lo = nlo;
    nodes[index].hi = nhi;
    if (count <= 4) {
      nodes[index].first = first;
      nodes[index].count = count;
      return;
    }
    const Vec3 extent = chi - clo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const uint32_t half = count / 2;
    std::nth_element(order.begin() + first, order.begin() + first + half, order.begin() + first + count,
                     [&](uint32_t u, uint32_t w) {
                       const double cu = centroid[u][axis], cw = centroid[w][axis];
                       return cu < cw || (cu == cw && u < w);
                     });
    self(self, first, half);
    nodes[index].second = static_cast<uint32_t>(nodes.size());
    self(self, first + half, count - half);
  };
  if (n > 0) build(build, 0, static_cast<uint32_t>(n));
}

bool Colliders::firstHit(const Vec3& from, const Vec3& to, ContactHit& hit) const {
  bool found = false;
  hit.fraction = std::numeric_limits<double>::infinity();
  for (const PlaneCollider& pl : planes) {
    const double d1 = dot(to - pl.point, pl.normal);
    if (d1 >= 0.0) continue;
    const double d0 = dot(from - pl.point, pl.normal);
    // A path that starts behind the plane (only possible by round-off or a scene that starts
    // inside) is pushed out at its start.
    const double s = d0 <= 0.0 ? 0.0 : d0 / (d0 - d1);
    if (s < hit.fraction) {
      Vec3 p = from + (to - from) * s;
      p -= pl.normal * dot(p - pl.point, pl.normal);  // exactly on the plane
      hit = {s, p, pl.normal, pl.material};
      found = true;
    }
  }
  if (meshes.empty()) return found;
  const Vec3 segLo = componentMin(from, to), segHi = componentMax(from, to);
  uint32_t stack[64];
  for (const TriangleCollider& tc : meshes) {
    if (tc.nodes.empty()) continue;
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const TriangleCollider::Node& node = tc.nodes[stack[--top]];
      if (!boxOverlap(segLo, segHi, node.lo, node.hi)) continue;
      if (node.count > 0) {
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
          const Triangle& tri = tc.mesh.triangles[tc.order[k]];
          Vec3 n;
          const double s = segmentTriangle(from, to, tc.mesh.positions[tri[0]], tc.mesh.positions[tri[1]],
                                           tc.mesh.positions[tri[2]], n);
          if (s >= 0.0 && s < hit.fraction) {
            hit = {s, from + (to - from) * s, n, tc.material};
            found = true;
          }
        }
      } else {
        const uint32_t self = static_cast<uint32_t>(&node - tc.nodes.data());
        stack[top++] = node.second;
        stack[top++] = self + 1;
      }
    }
  }
  return found;
}

Vec3 contactVelocity(const Vec3& velocity, const Vec3& n, const ContactMaterial& material, double restingSpeed,
                     bool resting) {
  const double vn = dot(velocity, n);
  if (vn >= 0.0) return velocity;  // already separating
  const Vec3 vt = velocity - n * vn;
  const double rebound = !resting && -vn > restingSpeed ? -material.restitution * vn : 0.0;
  const double normalImpulse = rebound - vn;  // per unit mass, > 0
  const double vtLen = length(vt);
  const double frictionImpulse = material.friction * normalImpulse;
  const Vec3 vtAfter = vtLen <= frictionImpulse ? Vec3{} : vt * ((vtLen - frictionImpulse) / vtLen);
  return vtAfter + n * rebound;
}

bool Colliders::resolve(const Vec3& from, Vec3& to, Vec3& velocity, bool resting, ContactHit* first) const {
  Vec3 start = from;
  bool touched = false;
  // A few rounds: hit, slide along the surface, possibly hit another collider.
  for (int round = 0; round < 4; ++round) {
    ContactHit hit;
    if (!firstHit(start, to, hit)) return touched;
    if (first && !touched) *first = hit;
    touched = true;
    const Vec3 before = velocity;
    const bool sustained = resting || round > 0;
    velocity = contactVelocity(velocity, hit.normal, hit.material, restingSpeed, sustained);
    // The rest of the path slides along the surface, slowed as the velocity was.
    Vec3 rest = to - hit.point;
    rest -= hit.normal * dot(rest, hit.normal);
    const Vec3 vtBefore = before - hit.normal * dot(before, hit.normal);
    const double vtb = length(vtBefore);
    const double scale = vtb > 0.0 ? length(velocity - hit.normal * dot(velocity, hit.normal)) / vtb : 0.0;
    // In sustained contact the vertex touched the surface all along the step (it began within the
    // skin), so friction held the part of the path before the hit too. Kept, that part let a
    // body that friction holds creep: each step's slide up to the hit escaped it (measured: a
    // soft cube on a 20 degree plate with friction 1 crept 0.4-1.1 mm/s, with the step).
    Vec3 slid = hit.point - start;
    slid -= hit.normal * dot(slid, hit.normal);
    start = hit.point + hit.normal * skin;
    if (sustained) start -= slid * (1.0 - scale);
    to = start + rest * scale;
  }
  // Out of rounds: stay at the last contact point rather than risk ending behind a surface.
  to = start;
  return touched;
}

bool Colliders::dampingLayers() const {
  for (const PlaneCollider& pl : planes) {
    if (pl.damping > 0.0 && pl.layer > 0.0) return true;
  }
  return false;
}

bool Colliders::dampInLayers(const Vec3& x, Vec3& velocity, double dt) const {
  bool inside = false;
  for (const PlaneCollider& pl : planes) {
    if (!(pl.damping > 0.0 && pl.layer > 0.0)) continue;
    const double height = dot(x - pl.point, pl.normal);
    if (height > pl.layer) continue;
    velocity -= pl.normal * (dot(velocity, pl.normal) * -std::expm1(-pl.damping * dt));
    inside = true;
  }
  return inside;
}

}  // namespace springy

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

namespace {

// The plane (point, normal) on the segment from -> to: the fraction of the crossing and the point
// on the plane, or a negative fraction when the segment ends in front of it.
double planeHit(const Vec3& point, const Vec3& normal, const Vec3& from, const Vec3& to, Vec3& on) {
  const double d1 = dot(to - point, normal);
  if (d1 >= 0.0) return -1.0;
  const double d0 = dot(from - point, normal);
  // A path that starts behind the plane (only possible by round-off or a scene that starts
  // inside) is pushed out at its start.
  const double s = d0 <= 0.0 ? 0.0 : d0 / (d0 - d1);
  on = from + (to - from) * s;
  on -= normal * dot(on - point, normal);  // exactly on the plane
  return s;
}

// The mesh's earliest crossing of the segment before `best` (its BVH), or a negative fraction.
double meshHit(const TriangleCollider& tc, const Vec3& from, const Vec3& to, double best, Vec3& normal) {
  double found = -1.0;
  if (tc.nodes.empty()) return found;
  const Vec3 segLo = componentMin(from, to), segHi = componentMax(from, to);
  uint32_t stack[64];
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
        if (s >= 0.0 && s < best) {
          best = found = s;
          normal = n;
        }
      }
    } else {
      const uint32_t self = static_cast<uint32_t>(&node - tc.nodes.data());
      stack[top++] = node.second;
      stack[top++] = self + 1;
    }
  }
  return found;
}

}  // namespace

bool Colliders::firstHit(const Vec3& from, const Vec3& to, ContactHit& hit, const ColliderPoses* poses) const {
  if (poses && poses->any) return firstHitMoving(from, to, hit, *poses, false);
  bool found = false;
  hit.fraction = std::numeric_limits<double>::infinity();
  for (const PlaneCollider& pl : planes) {
    Vec3 p;
    const double s = planeHit(pl.point, pl.normal, from, to, p);
    if (s >= 0.0 && s < hit.fraction) {
      hit = {s, p, pl.normal, pl.material, {}, p, pl.normal, p - from};
      found = true;
    }
  }
  for (const TriangleCollider& tc : meshes) {
    Vec3 n;
    const double s = meshHit(tc, from, to, hit.fraction, n);
    if (s >= 0.0) {
      const Vec3 p = from + (to - from) * s;
      hit = {s, p, n, tc.material, {}, p, n, p - from};
      found = true;
    }
  }
  return found;
}

bool Colliders::firstHitMoving(const Vec3& from, const Vec3& to, ContactHit& hit, const ColliderPoses& poses,
                               bool atEnd) const {
  // Each collider in its own frame: a still one as it is, a moving one at its pose at t0 for the
  // path's start and at t1 for its end (atEnd: both at t1, for the rest of a path that already
  // hit). The crossing found in the frame is placed back at the time of the hit.
  bool found = false;
  hit.fraction = std::numeric_limits<double>::infinity();
  const auto place = [&](const Movement& motion, const Pose& end, double s, const Vec3& local, const Vec3& localNormal,
                         const Vec3& localFrom, const ContactMaterial& material) {
    const double t = atEnd ? poses.t1 : poses.t0 + s * (poses.t1 - poses.t0);
    const Pose now = atEnd ? end : motion.pose(t);
    const Vec3 p = now.apply(local);
    hit = {s, p, now.rotate(localNormal), material, motion.velocityAt(p, t), end.apply(local),
           end.rotate(localNormal), end.rotate(local - localFrom)};
    found = true;
  };
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const PlaneCollider& pl = planes[i];
    const bool moves = pl.motion.moves();
    const Vec3 a = moves ? (atEnd ? poses.plane1[i] : poses.plane0[i]).inverse(from) : from;
    const Vec3 b = moves ? poses.plane1[i].inverse(to) : to;
    Vec3 p;
    const double s = planeHit(pl.point, pl.normal, a, b, p);
    if (s < 0.0 || s >= hit.fraction) continue;
    if (moves) {
      place(pl.motion, poses.plane1[i], s, p, pl.normal, a, pl.material);
    } else {
      hit = {s, p, pl.normal, pl.material, {}, p, pl.normal, p - from};
      found = true;
    }
  }
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const TriangleCollider& tc = meshes[i];
    const bool moves = tc.motion.moves();
    const Vec3 a = moves ? (atEnd ? poses.mesh1[i] : poses.mesh0[i]).inverse(from) : from;
    const Vec3 b = moves ? poses.mesh1[i].inverse(to) : to;
    Vec3 n;
    const double s = meshHit(tc, a, b, hit.fraction, n);
    if (s < 0.0) continue;
    const Vec3 p = a + (b - a) * s;
    if (moves) {
      place(tc.motion, poses.mesh1[i], s, p, n, a, tc.material);
    } else {
      hit = {s, p, n, tc.material, {}, p, n, p - from};
      found = true;
    }
  }
  return found;
}

bool Colliders::clearOfMovingPlanes(const Vec3& p, const ColliderPoses& poses) const {
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const PlaneCollider& pl = planes[i];
    const Vec3 q = pl.motion.moves() ? poses.plane1[i].inverse(p) : p;
    if (dot(q - pl.point, pl.normal) < 0.0) return false;
  }
  return true;
}

bool Colliders::moving() const {
  for (const PlaneCollider& pl : planes) {
    if (pl.motion.moves()) return true;
  }
  for (const TriangleCollider& tc : meshes) {
    if (tc.motion.moves()) return true;
  }
  return false;
}

void Colliders::posesOver(double t0, double t1, ColliderPoses& out) const {
  out.t0 = t0, out.t1 = t1;
  out.any = moving();
  if (!out.any) return;
  out.plane0.resize(planes.size()), out.plane1.resize(planes.size());
  out.mesh0.resize(meshes.size()), out.mesh1.resize(meshes.size());
  for (std::size_t i = 0; i < planes.size(); ++i) {
    if (!planes[i].motion.moves()) continue;
    out.plane0[i] = planes[i].motion.pose(t0);
    out.plane1[i] = planes[i].motion.pose(t1);
  }
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    if (!meshes[i].motion.moves()) continue;
    out.mesh0[i] = meshes[i].motion.pose(t0);
    out.mesh1[i] = meshes[i].motion.pose(t1);
  }
}

std::vector<double> Colliders::kinks() const {
  std::vector<double> times;
  for (const PlaneCollider& pl : planes) {
    for (double t : pl.motion.kinks()) times.push_back(t);
  }
  for (const TriangleCollider& tc : meshes) {
    for (double t : tc.motion.kinks()) times.push_back(t);
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
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

bool Colliders::resolve(const Vec3& from, Vec3& to, Vec3& velocity, bool resting, ContactHit* first,
                        const ColliderPoses* poses) const {
  Vec3 start = from;
  bool touched = false;
  const bool moving = poses && poses->any;
  // A few rounds: hit, slide along the surface, possibly hit another collider.
  for (int round = 0; round < 4; ++round) {
    ContactHit hit;
    // After a hit the rest of the path lies at the step's end (start and end both there).
    if (!(moving ? firstHitMoving(start, to, hit, *poses, round > 0) : firstHit(start, to, hit))) return touched;
    if (first && !touched) *first = hit;
    touched = true;
    const bool sustained = resting || round > 0;
    // The surface's own velocity carried along: restitution and friction act on the velocity
    // relative to it (zero for a still collider: the same arithmetic as before).
    const Vec3 vs = hit.surfaceVelocity;
    const Vec3& n = hit.endNormal;
    const Vec3 before = moving ? velocity - vs : velocity;
    const Vec3 after = contactVelocity(before, n, hit.material, restingSpeed, sustained);
    velocity = moving ? after + vs : after;
    // The rest of the path slides along the surface, slowed as the velocity was.
    Vec3 rest = to - hit.endPoint;
    rest -= n * dot(rest, n);
    const Vec3 vtBefore = before - n * dot(before, n);
    const double vtb = length(vtBefore);
    const double scale = vtb > 0.0 ? length(after - n * dot(after, n)) / vtb : 0.0;
    // In sustained contact the vertex touched the surface all along the step (it began within the
    // skin), so friction held the part of the path before the hit too. Kept, that part let a
    // body that friction holds creep: each step's slide up to the hit escaped it (measured: a
    // soft cube on a 20 degree plate with friction 1 crept 0.4-1.1 mm/s, with the step).
    Vec3 slid = hit.before;
    slid -= n * dot(slid, n);
    start = hit.endPoint + n * skin;
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

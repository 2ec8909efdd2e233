// springy: static colliders and continuous vertex contact.
//
// One interface for every static collider (the seed had planes and triangles in two code
// paths that could not be combined; docs/model.md §7, §14): after each step, every vertex's
// path from its old to its new position is tested against all colliders, and the EARLIEST hit
// along the path wins. A plane is a solid half-space (one-sided); a triangle mesh is a set of
// thin two-sided plates searched through a bounding volume hierarchy. At a hit the vertex is
// put back on the surface (plus a tiny skin), its velocity gets the collider's restitution
// along the normal and Coulomb friction along the surface (an impulse no larger than mu times
// the normal impulse), and the rest of its path continues as sliding along the surface.
//
// Contact never adds kinetic energy: the normal speed after contact is at most the speed
// before (restitution <= 1) and friction only removes tangential speed. Restitution applies
// to impacts only: a vertex that touched a collider within the last `restingWindow` seconds is
// in sustained contact and its hits are perfectly inelastic, as are impacts slower than
// `restingSpeed`. Without that, the springs pressing a resting body's lowest vertices into the
// ground would make them bounce off and back every few steps, forever. (Putting a vertex back on the
// surface moves it by less than one step's travel; the elastic energy of its springs changes
// by that much, O(dt^2).)
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/mesh.h"
#include "sim/motion.h"
#include "sim/vec3.h"

namespace springy {

struct ContactMaterial {
  double restitution = 0.6;  // ratio of rebound to impact normal speed, [0, 1]
  double friction = 0.3;     // Coulomb coefficient mu >= 0
};

struct PlaneCollider {
  Vec3 point;
  Vec3 normal;  // unit, pointing out of the solid
  ContactMaterial material;
  // Soft ground (mud, sand, turf): a viscous layer of this thickness [m] above the surface
  // damps the normal velocity of every vertex in it at `damping` [1/s]. A body rolling on it
  // is pressed into the layer at its leading side and lifts out at its trailing side; the layer
  // resists both, which is rolling resistance (the normal force shifted forward, as hysteresis
  // in a real contact does). 0: a hard surface.
  double damping = 0.0;
  double layer = 0.0;
  // A plane that moves on its own (point and normal are its placement at rest). Soft ground
  // does not move.
  Movement motion{};
};

// A static triangle mesh with its own BVH (built once by the constructor of Colliders).
struct TriangleCollider {
  std::string name;
  TriMesh mesh;
  ContactMaterial material;
  // BVH over triangles: nodes in depth-first order; a leaf holds [first, first + count) of
  // `order`, an inner node has its children at index + 1 and `second`.
  struct Node {
    Vec3 lo, hi;
    uint32_t first = 0, count = 0;  // leaf range (count > 0 for leaves)
    uint32_t second = 0;            // right child (inner nodes)
  };
  std::vector<Node> nodes;
  std::vector<uint32_t> order;
  // A mesh that moves on its own (mesh holds it at rest; the tree is over the rest positions).
  Movement motion{};
  void buildBvh();
};

struct ContactHit {
  double fraction;  // position of the hit along the path, [0, 1]
  Vec3 point;       // on the surface
  Vec3 normal;      // unit, toward the side the path came from
  ContactMaterial material;
  // A moving collider: the surface's velocity at the point when hit, and where the point and
  // the normal are at the end of the step (the surface carries them on). A still one: zero,
  // and the point and the normal.
  Vec3 surfaceVelocity;
  Vec3 endPoint, endNormal;
  Vec3 before;  // the path up to the hit, as the surface sees it (at the end of the step)
};

// Where the moving colliders are over one step: at its start t0 and its end t1 (Movement::pose).
// `any` false: nothing moves (the still colliders' code path, unchanged).
struct ColliderPoses {
  double t0 = 0.0, t1 = 0.0;
  bool any = false;
  std::vector<Pose> plane0, plane1, mesh0, mesh1;
};

struct Colliders {
  std::vector<PlaneCollider> planes;
  std::vector<TriangleCollider> meshes;
  double restingSpeed = 0.1;  // impacts slower than this [m/s] do not bounce
  double skin = 1e-6;         // distance a vertex is kept off a surface [m]
  double restingWindow = 0.02;  // contact within this time [s] counts as sustained (no bounce)

  bool empty() const { return planes.empty() && meshes.empty(); }
  // Whether a collider moves on its own.
  bool moving() const;
  // The moving colliders' poses at the step's start and end (out.any: some collider moves).
  void posesOver(double t0, double t1, ColliderPoses& out) const;
  // Every moving collider's keyframe times, sorted, once each.
  std::vector<double> kinks() const;
  // Earliest hit on the segment from `from` to `to` over all colliders; false if none. With
  // `poses` (some collider moves), the path is the vertex's from the step's start to its end,
  // and each moving collider is tested in its own frame: the path from where it is at t0 to
  // where it is at t1 relative to it, so a surface faster than the vertex does not pass
  // through it (continuous contact against the moving surface).
  bool firstHit(const Vec3& from, const Vec3& to, ContactHit& hit, const ColliderPoses* poses = nullptr) const;
  // Resolves one vertex's path: returns the corrected end position and updates `velocity`.
  // `resting`: the vertex is in sustained contact (touched a collider within restingWindow).
  // Returns true if any contact happened; `first`, when given, receives the first hit. At a
  // moving collider the velocity relative to the surface gets the restitution and the friction
  // (the surface carries what rests on it).
  bool resolve(const Vec3& from, Vec3& to, Vec3& velocity, bool resting, ContactHit* first = nullptr,
               const ColliderPoses* poses = nullptr) const;
  // No collider can be hit on a path that ends at p: there are no triangle meshes and p is on
  // or in front of every plane (firstHit finds nothing then; a moving plane where it is at the
  // step's end). Inline: most vertices of most steps take only this test.
  bool clearAt(const Vec3& p, const ColliderPoses* poses = nullptr) const {
    if (!meshes.empty()) return false;
    if (poses && poses->any) return clearOfMovingPlanes(p, *poses);
    for (const PlaneCollider& pl : planes) {
      if (dot(p - pl.point, pl.normal) < 0.0) return false;
    }
    return true;
  }
  // Largest depth of a point behind any plane (0 when in front of all) [m]; with `planePoses`
  // (one per plane), a moving plane where that pose puts it.
  double planePenetration(const Vec3& p, const Pose* planePoses = nullptr) const {
    double depth = 0.0;
    for (std::size_t i = 0; i < planes.size(); ++i) {
      const PlaneCollider& pl = planes[i];
      const Vec3 q = planePoses && pl.motion.moves() ? planePoses[i].inverse(p) : p;
      depth = std::max(depth, -dot(q - pl.point, pl.normal));
    }
    return depth;
  }
  // Whether any plane has a damping layer.
  bool dampingLayers() const;
  // Damps the normal velocity of a vertex at x inside a plane's damping layer over a step dt:
  // v_n -> v_n exp(-damping dt) (exact for the layer's linear drag, so never more than v_n).
  // Returns whether the vertex is in a layer.
  bool dampInLayers(const Vec3& x, Vec3& velocity, double dt) const;

 private:
  bool clearOfMovingPlanes(const Vec3& p, const ColliderPoses& poses) const;
  bool firstHitMoving(const Vec3& from, const Vec3& to, ContactHit& hit, const ColliderPoses& poses, bool atEnd) const;
};

// Velocity after an impact with a surface of unit normal n (restitution along n, Coulomb
// friction along the surface). Slower impacts than `restingSpeed`, and any hit in resting
// contact, are inelastic.
Vec3 contactVelocity(const Vec3& velocity, const Vec3& n, const ContactMaterial& material, double restingSpeed,
                     bool resting = false);

}  // namespace springy

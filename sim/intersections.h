// springy: the audit of contact (issue 16): triangles of bodies that cross each other.
//
// Two triangles intersect when an edge of one passes through the other (Moeller 1997, "A fast
// triangle-triangle intersection test", reduced to its segment-triangle core; coplanar
// triangles, which touch without crossing, are not counted). The audit tests every pair of
// bodies that take part in contact and, within a body with self contact, every pair of faces that
// share no vertex, through a tree over each body's faces (sim/contact_bvh.h): a run whose contact
// let anything through is caught, whatever the contact stage believed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim/model.h"

namespace springy {

struct Intersection {
  uint32_t bodyA = 0, faceA = 0;  // faces: global indices into Model::faces
  uint32_t bodyB = 0, faceB = 0;  // bodyA <= bodyB
  Vec3 point;                     // where an edge of one passes through the other
};

// The crossing triangle pairs at positions x, in body and face order; at most `limit` of them
// (the count stops there).
std::vector<Intersection> findIntersections(const Model& model, const std::vector<Vec3>& x, std::size_t limit = 64);

// A body's face and a collider mesh's triangle that cross (the audit against colliders): an
// edge of one passes through the other. A body through a still or a moving collider (at its
// pose at the time given) is caught as one through another body is.
struct ColliderCrossing {
  uint32_t body = 0, face = 0;          // face: global index into Model::faces
  uint32_t collider = 0, triangle = 0;  // into Model::colliders.meshes and its mesh's triangles
  Vec3 point;
};

// The crossings of bodies' faces with collider meshes' triangles at positions x and time t, in
// collider, body and face order; at most `limit` of them.
std::vector<ColliderCrossing> findColliderCrossings(const Model& model, const std::vector<Vec3>& x, double t,
                                                    std::size_t limit = 64);

// Whether the segment p q passes through the triangle (a, b, c) (its ends strictly on opposite
// sides of the plane, the crossing inside or on the triangle); if so, where.
bool segmentCrossesTriangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& point);

}  // namespace springy

#include "sim/contact.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace springy {
namespace {

// A pair already closer than its thickness is pushed apart at this fraction of the overlap per
// step (Bridson et al. 2002 §7.2 use 0.1 for their repulsion), but never faster than the overlap
// in kSeparationTime. The push moves the positions only: as a velocity it would be 0.1 (h - d) / dt,
// which at a small step is metres per second, and a body resting on another would keep bouncing
// off it (measured: vertices of a resting stack at 1 m/s with the push kept in the velocity).
// The bound: per step alone, at 0.25 ms steps the push moved a surface that started inside the
// thickness at 10 m/s, far faster than the rest of its body could follow; measured, a cube set
// down 2.4 cm inside a pinned slab's thickness gained 2 J of elastic energy in 33 ms and the
// monitor stopped the run. With the bound it settles onto the slab (tilted 20 degrees, friction
// 1) and stays there to 0.1 mm over 4 s.
constexpr double kSeparationRate = 0.1;
constexpr double kSeparationTime = 0.05;  // [s]

bool sharesVertex(const std::array<uint32_t, 2>& e, const std::array<uint32_t, 2>& f) {
  return e[0] == f[0] || e[0] == f[1] || e[1] == f[0] || e[1] == f[1];
}

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// A triangle collider's edges that something can pass over without a vertex crossing a face:
// border edges (one face), edges of three or more faces, and creases (two faces not coplanar).
// Each once, as sorted (lower, higher) collider-local vertex indices, in sorted order.
std::vector<std::array<uint32_t, 2>> sharpEdges(const TriMesh& mesh) {
  struct Side {
    std::array<uint32_t, 2> edge;
    uint32_t face;
  };
  std::vector<Side> sides;
  for (uint32_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = t[static_cast<std::size_t>(k)], j = t[static_cast<std::size_t>((k + 1) % 3)];
      sides.push_back({{std::min(i, j), std::max(i, j)}, f});
    }
  }
  std::sort(sides.begin(), sides.end(),
            [](const Side& a, const Side& b) { return a.edge < b.edge || (a.edge == b.edge && a.face < b.face); });
  const auto normal = [&](uint32_t f) {
    const Triangle& t = mesh.triangles[f];
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    return normalized(cross(b - a, c - a));
  };
  std::vector<std::array<uint32_t, 2>> sharp;
  for (std::size_t k = 0; k < sides.size();) {
    std::size_t end = k;
    while (end < sides.size() && sides[end].edge == sides[k].edge) ++end;
    // Coplanar: the normals parallel (either way round, as a plate is two-sided) to 1e-6 rad.
    const bool flat = end - k == 2 && length(cross(normal(sides[k].face), normal(sides[k + 1].face))) < 1e-6;
    if (!flat) sharp.push_back(sides[k].edge);
    k = end;
  }
  return sharp;
}

// The pairs of `kept` (a superset: found with fat boxes that hold the current boxes) whose current
// boxes overlap, in its (sorted) order. A full pass takes them all. A later pass takes only the
// pairs with a primitive whose path changed in the pass before (`dirtyA`, `dirtyB`): a pair of two
// unchanged primitives was tested then and needed no impulse, or they would have changed, so it
// needs none now. Either way exactly the pairs whose boxes overlap (of those), so that every pass
// tests the same pairs in the same order as one search of two trees over the current boxes would.
template <class BoxA, class BoxB, class DirtyA, class DirtyB>
void candidatePairs(bool full, const std::vector<PrimitivePair>& kept, const BoxA& boxA, const BoxB& boxB,
                    const DirtyA& dirtyA, const DirtyB& dirtyB, std::vector<PrimitivePair>& out) {
  out.clear();
  for (const PrimitivePair& p : kept) {
    if (!full && !dirtyA(p.a) && !dirtyB(p.b)) continue;
    if (overlaps(boxA(p.a), boxB(p.b))) out.push_back(p);
  }
}

constexpr auto kNeverDirty = [](uint32_t) { return false; };

bool inside(const Box& box, const Box& in) {
  return in.lo.x <= box.lo.x && in.lo.y <= box.lo.y && in.lo.z <= box.lo.z && box.hi.x <= in.hi.x &&
         box.hi.y <= in.hi.y && box.hi.z <= in.hi.z;
}

}  // namespace

bool BodyContacts::needed(const Model& model) {
  uint32_t taking = 0;
  for (const BodyInfo& b : model.bodies) {
    if (b.selfContact) return true;
    if (b.contact) ++taking;
  }
  if (taking >= 2) return true;
  if (taking == 0) return false;
  for (const TriangleCollider& c : model.colliders.meshes) {
    if (!c.motion.moves() && !sharpEdges(c.mesh).empty()) return true;
  }
  return false;
}

void BodyContacts::addStatics() {
  const Model& model = *model_;
  for (uint32_t c = 0; c < model.colliders.meshes.size(); ++c) {
    const TriangleCollider& collider = model.colliders.meshes[c];
    // A moving mesh's edges are not among the still primitives: its triangles stop the vertices
    // that meet them (sim/colliders.h), and its edges meet a body's only there.
    if (collider.motion.moves()) continue;
    Static s;
    s.collider = c;
    s.friction = collider.material.friction;
    s.restitution = collider.material.restitution;
    s.edges = sharpEdges(collider.mesh);
    if (s.edges.empty()) continue;
    const uint32_t first = vertexCount_ + static_cast<uint32_t>(staticPosition_.size());
    for (auto& e : s.edges) {
      s.vertices.push_back(e[0]), s.vertices.push_back(e[1]);
      e = {first + e[0], first + e[1]};
    }
    std::sort(s.vertices.begin(), s.vertices.end());
    s.vertices.erase(std::unique(s.vertices.begin(), s.vertices.end()), s.vertices.end());
    for (uint32_t& v : s.vertices) v += first;
    staticPosition_.insert(staticPosition_.end(), collider.mesh.positions.begin(), collider.mesh.positions.end());
    statics_.push_back(std::move(s));
  }
  // The trees over the still primitives, built once (boxes without margin: a body's boxes carry
  // half its thickness, the whole thickness of a pair with a collider).
  for (Static& s : statics_) {
    boxes_.clear();
    for (uint32_t v : s.vertices) boxes_.push_back(sweptBox(path(v, {}, 0.0), 0.0));
    s.vertexTree.build(boxes_);
    boxes_.clear();
    for (const auto& e : s.edges) boxes_.push_back(sweptBox(path(e[0], {}, 0.0), path(e[1], {}, 0.0), 0.0));
    s.edgeTree.build(boxes_);
    s.box = boxes_.front();
    for (const Box& b : boxes_) s.box = merged(s.box, b);
  }
}

BodyContacts::BodyContacts(const Model& model) : model_(&model), invMass_(model.invMass.data()) {
  vertexCount_ = static_cast<uint32_t>(model.vertexCount());
  addStatics();
  const std::size_t n = vertexCount_ + staticPosition_.size();
  u_.assign(n, Vec3{});
  u0_.assign(n, Vec3{});
  push_.assign(n, Vec3{});
  changed_.assign(n, 0);
  touched_.assign(n, 0);
  contactOf_.assign(n, 0);
  dirty_.assign(n, 0);
  stopped_.assign(n, 0);
  group_.resize(n);
  groupMomentum_.assign(n, Vec3{});
  groupMass_.assign(n, 0.0);
  bodies_.resize(model.bodies.size());
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    const BodyInfo& info = model.bodies[b];
    if (!info.contact && !info.selfContact) continue;
    addActive(b);
  }
  setCandidateBudget();
  vertexBox_.assign(vertexCount_, Box{});
  fatBox_.assign(vertexCount_, Box{});
  kept_.resize(active_.size() * (active_.size() + statics_.size()));
  vertexBody_.assign(vertexCount_, 0);
  for (uint32_t b : active_) {
    const BodyInfo& info = model.bodies[b];
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) vertexBody_[i] = b;
  }
  for (uint32_t b : active_) {
    if (bodies_[b].self) findRestPairs(b);
  }
}

void BodyContacts::addActive(uint32_t b) {
  const Model& model = *model_;
  const BodyInfo& info = model.bodies[b];
  Body& body = bodies_[b];
  active_.push_back(b);
  body.self = info.selfContact;
  body.friction = info.contactFriction;
  body.restitution = info.contactRestitution;
  // The edges, each once, from the faces.
  for (uint32_t f = info.firstFace; f < info.firstFace + info.faceCount; ++f) {
    const Triangle& t = model.faces[f];
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = t[static_cast<std::size_t>(k)], j = t[static_cast<std::size_t>((k + 1) % 3)];
      body.edges.push_back({std::min(i, j), std::max(i, j)});
    }
  }
  std::sort(body.edges.begin(), body.edges.end());
  body.edges.erase(std::unique(body.edges.begin(), body.edges.end()), body.edges.end());
  double sum = 0.0;
  for (const auto& e : body.edges) sum += length(model.restPosition[e[1]] - model.restPosition[e[0]]);
  body.thickness = info.contactThickness > 0.0 ? info.contactThickness
                                               : kDefaultThicknessFactor * sum /
                                                     static_cast<double>(std::max<std::size_t>(1, body.edges.size()));
}

void BodyContacts::setCandidateBudget() {
  const Model& model = *model_;
  double primitives = 0.0;
  for (uint32_t b : active_) {
    primitives +=
        model.bodies[b].vertexCount + model.bodies[b].faceCount + static_cast<double>(bodies_[b].edges.size());
  }
  for (const Static& s : statics_) primitives += static_cast<double>(s.vertices.size() + s.edges.size());
  maxCandidates_ = kMaxCandidatesPerPrimitive * primitives;
}

void BodyContacts::findRestPairs(uint32_t b) {
  const Model& model = *model_;
  Body& body = bodies_[b];
  const BodyInfo& info = model.bodies[b];
  const std::vector<Vec3>& x = model.restPosition;
  const double h = body.thickness;
  std::vector<Box> vertexBoxes, faceBoxes, edgeBoxes;
  for (uint32_t i = 0; i < info.vertexCount; ++i)
    vertexBoxes.push_back(sweptBox({x[info.firstVertex + i], x[info.firstVertex + i]}, h));
  for (uint32_t f = 0; f < info.faceCount; ++f) {
    const Triangle& t = model.faces[info.firstFace + f];
    faceBoxes.push_back(sweptBox({x[t[0]], x[t[0]]}, {x[t[1]], x[t[1]]}, {x[t[2]], x[t[2]]}, h));
  }
  for (const auto& e : body.edges) edgeBoxes.push_back(sweptBox({x[e[0]], x[e[0]]}, {x[e[1]], x[e[1]]}, h));
  Bvh vt, ft, et;
  vt.build(vertexBoxes), ft.build(faceBoxes), et.build(edgeBoxes);
  std::vector<PrimitivePair> pairs;
  overlapPairs(
      vt, ft,
      [&](uint32_t v, uint32_t f) {
        const Triangle& t = model.faces[info.firstFace + f];
        const uint32_t i = info.firstVertex + v;
        return t[0] == i || t[1] == i || t[2] == i;
      },
      pairs);
  for (const PrimitivePair& p : pairs) {
    const Triangle& t = model.faces[info.firstFace + p.b];
    const PointTriangleClosest c = closestPointTriangle(x[info.firstVertex + p.a], x[t[0]], x[t[1]], x[t[2]]);
    if (c.distanceSquared < h * h) body.restVertexFace.push_back(p);
  }
  pairs.clear();
  selfOverlapPairs(
      et, [&](uint32_t e, uint32_t f) { return sharesVertex(body.edges[e], body.edges[f]); }, pairs);
  for (const PrimitivePair& p : pairs) {
    const auto &e = body.edges[p.a], &f = body.edges[p.b];
    const SegmentSegmentClosest c = closestSegmentSegment(x[e[0]], x[e[1]], x[f[0]], x[f[1]]);
    if (c.distanceSquared < h * h) body.restEdgeEdge.push_back(p);
  }
}

void BodyContacts::refreshFat(uint32_t b) {
  const Model& model = *model_;
  Body& body = bodies_[b];
  const BodyInfo& info = model.bodies[b];
  const double margin = kCandidateMarginFactor * body.thickness;
  const Vec3 m{margin, margin, margin};
  const auto update = [&](Bvh& tree) {
    if (tree.primitiveCount() != boxes_.size() || tree.nodes().empty()) {
      tree.build(boxes_);
    } else {
      tree.refit(boxes_);
      if (tree.needsRebuild()) tree.rebuild();
    }
  };
  boxes_.clear();
  for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
    fatBox_[i] = {vertexBox_[i].lo - m, vertexBox_[i].hi + m};
    boxes_.push_back(fatBox_[i]);
  }
  update(body.vertexTree);
  boxes_.clear();
  for (const auto& e : body.edges) boxes_.push_back(merged(fatBox_[e[0]], fatBox_[e[1]]));
  update(body.edgeTree);
  boxes_.clear();
  for (uint32_t f = info.firstFace; f < info.firstFace + info.faceCount; ++f) {
    const Triangle& t = model.faces[f];
    boxes_.push_back(merged(merged(fatBox_[t[0]], fatBox_[t[1]]), fatBox_[t[2]]));
  }
  update(body.faceTree);
  body.fat = ++fatGeneration_;
  body.outside = false;
}

void BodyContacts::trimKept(Candidates& kept) const {
  std::size_t size = 0;
  for (const auto& list : kept.lists) size += list.size();
  if (static_cast<double>(size) <= maxCandidates_) return;
  // Too many to keep (bodies packed inside each other, or blown up): found anew next time.
  kept = Candidates{};
}

void BodyContacts::addVertexFace(uint32_t i, const Triangle& t, const std::vector<Vec3>& x0, double dt, double h,
                                 double friction, double restitution, bool still, std::vector<Contact>& out) const {
  VertexTriangleContact c;
  if (!vertexTriangleImpact(path(i, x0, dt), path(t[0], x0, dt), path(t[1], x0, dt), path(t[2], x0, dt), h, c)) return;
  out.push_back({{i, t[0], t[1], t[2]},
                 {1.0, -c.weight[0], -c.weight[1], -c.weight[2]},
                 c.normal,
                 c.distance,
                 h,
                 friction,
                 restitution,
                 still});
}

bool BodyContacts::pairContacts(uint32_t a, uint32_t b, Candidates& kept, const std::vector<Vec3>& x0, double dt,
                                std::vector<Contact>& out, uint64_t& candidates) {
  const Model& model = *model_;
  const Body &A = bodies_[a], &B = bodies_[b];
  const bool self = a == b;
  const double h = 0.5 * (A.thickness + B.thickness);
  const double mu = std::max(A.friction, B.friction) > 0.0 ? std::sqrt(A.friction * B.friction) : 0.0;
  const double restitution = std::max(A.restitution, B.restitution);
  const auto motion = [&](uint32_t i) { return path(i, x0, dt); };
  // The kept candidates, found anew (one search of the fat trees) when a body's fat boxes changed.
  const bool find = kept.fatA != A.fat || kept.fatB != B.fat;
  if (find) {
    for (auto& list : kept.lists) list.clear();
    kept.fatA = A.fat, kept.fatB = B.fat;
  }
  // Vertices of `vb` against faces of `fb`.
  const auto vertexFace = [&](uint32_t vb, uint32_t fb, std::vector<PrimitivePair>& list) {
    const Body &V = bodies_[vb], &F = bodies_[fb];
    const BodyInfo &vi = model.bodies[vb], &fi = model.bodies[fb];
    if (find && self) {
      overlapPairs(
          V.vertexTree, F.faceTree,
          [&](uint32_t v, uint32_t f) {
            const Triangle& t = model.faces[fi.firstFace + f];
            const uint32_t i = vi.firstVertex + v;
            return t[0] == i || t[1] == i || t[2] == i ||
                   std::binary_search(V.restVertexFace.begin(), V.restVertexFace.end(), PrimitivePair{v, f});
          },
          list);
    } else if (find) {
      overlapPairs(V.vertexTree, F.faceTree, list);
    }
    candidatePairs(
        full_, list, [&](uint32_t v) -> const Box& { return vertexBox_[vi.firstVertex + v]; },
        [&](uint32_t f) { return faceBox(model.faces[fi.firstFace + f]); },
        [&](uint32_t v) { return dirty_[vi.firstVertex + v] != 0; },
        [&](uint32_t f) { return dirtyCorner(model.faces[fi.firstFace + f]); }, pairs_);
    if (!withinBudget(candidates)) return false;
    for (const PrimitivePair& p : pairs_) {
      const uint32_t i = vi.firstVertex + p.a;
      const Triangle& t = model.faces[fi.firstFace + p.b];
      addVertexFace(i, t, x0, dt, h, mu, restitution, false, out);
    }
    return true;
  };
  // Edges against edges.
  const auto edgeEdge = [&]() {
    std::vector<PrimitivePair>& list = kept.lists[2];
    if (find && self) {
      selfOverlapPairs(
          A.edgeTree,
          [&](uint32_t e, uint32_t f) {
            return sharesVertex(A.edges[e], A.edges[f]) ||
                   std::binary_search(A.restEdgeEdge.begin(), A.restEdgeEdge.end(), PrimitivePair{e, f});
          },
          list);
    } else if (find) {
      overlapPairs(A.edgeTree, B.edgeTree, list);
    }
    candidatePairs(
        full_, list, [&](uint32_t e) { return edgeBox(A.edges[e]); }, [&](uint32_t e) { return edgeBox(B.edges[e]); },
        [&](uint32_t e) { return dirtyEdge(A.edges[e]); }, [&](uint32_t e) { return dirtyEdge(B.edges[e]); }, pairs_);
    if (!withinBudget(candidates)) return false;
    for (const PrimitivePair& p : pairs_) {
      const auto &e = A.edges[p.a], &f = B.edges[p.b];
      EdgeEdgeContact c;
      if (!edgeEdgeImpact(motion(e[0]), motion(e[1]), motion(f[0]), motion(f[1]), h, c)) continue;
      out.push_back(
          {{e[0], e[1], f[0], f[1]}, {1.0 - c.a, c.a, -(1.0 - c.b), -c.b}, c.normal, c.distance, h, mu, restitution});
    }
    return true;
  };
  const bool ok = vertexFace(a, b, kept.lists[0]) && (self || vertexFace(b, a, kept.lists[1])) && edgeEdge();
  // An overflow leaves the lists incomplete: found anew next time.
  if (!ok) kept = Candidates{};
  trimKept(kept);
  return ok;
}

bool BodyContacts::staticContacts(uint32_t b, const Static& s, Candidates& kept, const std::vector<Vec3>& x0, double dt,
                                  std::vector<Contact>& out, uint64_t& candidates) {
  const Model& model = *model_;
  const Body& B = bodies_[b];
  const BodyInfo& info = model.bodies[b];
  const double h = 0.5 * B.thickness;
  const auto motion = [&](uint32_t i) { return path(i, x0, dt); };
  const bool find = kept.fatA != B.fat;
  if (find) {
    for (auto& list : kept.lists) list.clear();
    overlapPairs(B.edgeTree, s.edgeTree, kept.lists[0]);
    overlapPairs(s.vertexTree, B.faceTree, kept.lists[1]);
    kept.fatA = B.fat, kept.fatB = 0;
  }
  const auto ok = [&]() {
    // The body's edges against the collider's sharp edges.
    candidatePairs(
        full_, kept.lists[0], [&](uint32_t e) { return edgeBox(B.edges[e]); },
        [&](uint32_t e) -> const Box& { return s.edgeTree.boxOf(e); },
        [&](uint32_t e) { return dirtyEdge(B.edges[e]); }, kNeverDirty, pairs_);
    if (!withinBudget(candidates)) return false;
    for (const PrimitivePair& p : pairs_) {
      const auto &e = B.edges[p.a], &f = s.edges[p.b];
      EdgeEdgeContact c;
      if (!edgeEdgeImpact(motion(e[0]), motion(e[1]), motion(f[0]), motion(f[1]), h, c)) continue;
      out.push_back({{e[0], e[1], f[0], f[1]},
                     {1.0 - c.a, c.a, -(1.0 - c.b), -c.b},
                     c.normal,
                     c.distance,
                     h,
                     s.friction,
                     s.restitution,
                     true});
    }
    // The collider's corners against the body's faces (the vertex is the still side: weight 1 on
    // it, so the normal points from the face to the corner).
    candidatePairs(
        full_, kept.lists[1], [&](uint32_t v) -> const Box& { return s.vertexTree.boxOf(v); },
        [&](uint32_t f) { return faceBox(model.faces[info.firstFace + f]); }, kNeverDirty,
        [&](uint32_t f) { return dirtyCorner(model.faces[info.firstFace + f]); }, pairs_);
    if (!withinBudget(candidates)) return false;
    for (const PrimitivePair& p : pairs_) {
      const uint32_t i = s.vertices[p.a];
      const Triangle& t = model.faces[info.firstFace + p.b];
      addVertexFace(i, t, x0, dt, h, s.friction, s.restitution, true, out);
    }
    return true;
  }();
  trimKept(kept);
  return ok;
}

void BodyContacts::sweepBodies(const std::vector<Vec3>& x0, double dt) {
  const Model& model = *model_;
  // Each moved body's swept box first, from its vertices' (one pass over them, which also tells
  // whether each is still inside its fat box): the boxes of a body that is near no other and has
  // no self contact are not needed this pass.
  for (uint32_t b : active_) {
    const BodyInfo& info = model.bodies[b];
    Body& body = bodies_[b];
    if (!full_ || !body.moved) continue;
    Box box{x0[info.firstVertex], x0[info.firstVertex]};
    bool outside = false;
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      const Box vertex = sweptBox(Motion{x0[i], x0[i] + u_[i] * dt}, 0.5 * body.thickness);
      vertexBox_[i] = vertex;
      outside = outside || !inside(vertex, fatBox_[i]);
      box = merged(box, vertex);
    }
    body.box = box;
    body.outside = outside;
  }
  // After the first pass only the vertices whose paths changed in the pass before (dirty_) have
  // new boxes. A body's box grows over them (it may be larger than its vertices' now: a pair it
  // makes near in vain finds no candidates, as their boxes do not overlap).
  for (uint32_t i : dirtyList_) {
    Body& body = bodies_[vertexBody_[i]];
    const Box vertex = sweptBox(Motion{x0[i], x0[i] + u_[i] * dt}, 0.5 * body.thickness);
    vertexBox_[i] = vertex;
    body.outside = body.outside || !inside(vertex, fatBox_[i]);
    body.box = merged(body.box, vertex);
  }
}

void BodyContacts::markNearBodies() {
  const Model& model = *model_;
  for (uint32_t b : active_) {
    bodies_[b].near = bodies_[b].self;
    for (const Static& s : statics_)
      bodies_[b].near = bodies_[b].near || (model.bodies[b].contact && overlaps(bodies_[b].box, s.box));
  }
  for (std::size_t k = 0; k < active_.size(); ++k) {
    for (std::size_t l = k + 1; l < active_.size(); ++l) {
      Body &A = bodies_[active_[k]], &B = bodies_[active_[l]];
      if (model.bodies[active_[k]].contact && model.bodies[active_[l]].contact && overlaps(A.box, B.box)) {
        A.near = B.near = true;
      }
    }
  }
  // New fat boxes for a near body if a vertex left its own.
  for (uint32_t b : active_) {
    Body& body = bodies_[b];
    if (body.near && (body.fat == 0 || body.outside)) refreshFat(b);
  }
}

bool BodyContacts::findContacts(const std::vector<Vec3>& x0, double dt, std::vector<Contact>& out, uint64_t* counted) {
  uint64_t candidates = 0;
  const Model& model = *model_;
  out.clear();
  sweepBodies(x0, dt);
  markNearBodies();
  // The pairs with a body that moved since the last pass (all on the first): a pair of two bodies
  // that did not has had every contact satisfied in that pass, or they would have moved. The kept
  // candidates of pairs that are not near are dropped on the first pass.
  const std::size_t n = active_.size();
  bool ok = true;
  for (std::size_t k = 0; ok && k < n; ++k) {
    const uint32_t a = active_[k];
    const bool movedA = bodies_[a].moved;
    if (bodies_[a].self && movedA) ok = pairContacts(a, a, keptAt(k * n + k), x0, dt, out, candidates);
    for (std::size_t l = k + 1; ok && model.bodies[a].contact && l < n; ++l) {
      const uint32_t b = active_[l];
      const bool pair = model.bodies[b].contact && overlaps(bodies_[a].box, bodies_[b].box);
      if ((movedA || bodies_[b].moved) && pair) {
        ok = pairContacts(a, b, keptAt(k * n + l), x0, dt, out, candidates);
        if (!ok) overflowPair_ = {a, b};
      } else if (full_ && !pair) {
        kept_[k * n + l].reset();
      }
    }
    for (std::size_t s = 0; ok && movedA && model.bodies[a].contact && s < statics_.size(); ++s) {
      const std::size_t index = n * n + k * statics_.size() + s;
      if (overlaps(bodies_[a].box, statics_[s].box)) {
        ok = staticContacts(a, statics_[s], keptAt(index), x0, dt, out, candidates);
      } else if (full_) {
        kept_[index].reset();
      }
    }
    if (!ok && overflowPair_[0] != a) overflowPair_ = {a, a};
  }
  if (counted) *counted += candidates;
  return ok;
}

bool BodyContacts::overflow(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt) {
  // The impulses applied so far are kept (each is equal and opposite); the search is abandoned.
  ++last_.overflows;
  const Model& model = *model_;
  bool changed = false;
  for (uint32_t b : active_) {
    const BodyInfo& info = model.bodies[b];
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      if (!changed_[i]) continue;
      x1[i] = x0[i] + u_[i] * dt;
      v1[i] += u_[i] - u0_[i] - push_[i];
      changed = true;
    }
  }
  return changed;
}

double BodyContacts::normalSpeed(const Contact& c) const {
  double s = 0.0;
  for (int k = 0; k < 4; ++k) s += c.weight[k] * dot(u_[c.vertex[k]], c.normal);
  return s;
}

bool BodyContacts::impulse(const Contact& c, double dt, bool impact) {
  const double vn = normalSpeed(c);
  // The velocity's target: an impact from outside the thickness (the first pass, faster than the
  // resting speed) rebounds by the restitution; any other contact stops approaching. A pair
  // already inside the thickness is also pushed apart slowly, in position only (kSeparationRate).
  // No push against a static collider: its own stage keeps a body's vertices on its faces' skin
  // (sim/colliders.h), so a body resting on a plate's rim would be pushed off it here and put back
  // there, step after step: measured, a ball resting on a box's rim in scenes/pile.toml vibrated
  // with 7 J of kinetic energy while its centroid stood still.
  double bounce = 0.0, push = 0.0;
  if (c.distance < c.thickness) {
    if (!c.still) push = (c.thickness - c.distance) * std::min(kSeparationRate / dt, 1.0 / kSeparationTime);
  } else if (impact && -vn > model_->colliders.restingSpeed) {
    bounce = -c.restitution * vn;
  }
  const double target = bounce + push;
  if (!(vn < target)) return false;
  double inverseMass = 0.0;  // of the contact point along the normal: sum w_k^2 / m_k
  Vec3 relative;
  for (int k = 0; k < 4; ++k) {
    inverseMass += c.weight[k] * c.weight[k] * this->inverseMass(c.vertex[k]);
    relative += u_[c.vertex[k]] * c.weight[k];
  }
  if (!(inverseMass > 0.0)) return false;  // every corner pinned
  const double j = (target - vn) / inverseMass;
  // The part of j that changes the velocity (up to the bounce); the rest only moves positions.
  const double jVelocity = std::clamp((bounce - vn) / inverseMass, 0.0, j);
  Vec3 change = c.normal * j;
  // Coulomb friction: at most mu times the velocity's impulse off the relative tangential speed
  // (which it may stop, not reverse).
  const Vec3 tangential = relative - c.normal * dot(relative, c.normal);
  const double slip = length(tangential);
  if (c.friction > 0.0 && slip > 0.0) {
    change -= tangential * (std::min(c.friction * jVelocity, slip / inverseMass) / slip);
  }
  const Vec3 pushed = c.normal * (j - jVelocity);
  applied_.push_back(c);
  applied_.back().bounce = bounce;
  for (int k = 0; k < 4; ++k) {
    const uint32_t i = c.vertex[k];
    const double w = this->inverseMass(i);
    if (w == 0.0 || c.weight[k] == 0.0) continue;
    u_[i] += change * (c.weight[k] * w);
    push_[i] += pushed * (c.weight[k] * w);
    touch(i);
  }
  return true;
}

void BodyContacts::settleEndVelocities(std::vector<Vec3>& v1) {
  // The impulses aim at the path's mean velocity u = (x1 - x0) / dt and add the same change to
  // the end velocity v1. Only symplectic Euler ends its step with v1 = u; RK4 ends it about a dt / 2
  // further along (a is the acceleration), so at a resting contact, where the springs press the
  // surfaces together, v1 kept approaching by that much after every step. Measured: a ball resting
  // in the saddle of three others under RK4 kept its contact vertices at 8 cm/s (RMS) and
  // 5e-5 J that did not die away, and the heap crept 0.5 mm/s. So v1 itself is brought to the
  // impulse's aim at every contact that took one, with friction as in impulse() (no push: that
  // moves positions only), in the same order, a few sweeps (Gauss-Seidel).
  const auto velocity = [&](uint32_t i) { return i < vertexCount_ ? v1[i] : Vec3{}; };
  for (int sweep = 0; sweep < kImpulsePasses; ++sweep) {
    bool applied = false;
    for (const Contact& c : applied_) {
      double vn = 0.0, inverseMass = 0.0;
      Vec3 relative;
      bool stopped = false;
      for (int k = 0; k < 4; ++k) {
        const uint32_t i = c.vertex[k];
        stopped = stopped || (i < vertexCount_ && stopped_[i]);
        relative += velocity(i) * c.weight[k];
        inverseMass += c.weight[k] * c.weight[k] * this->inverseMass(i);
      }
      // A stopped vertex ends with its group's velocity (below), which keeps the momentum.
      if (stopped || !(inverseMass > 0.0)) continue;
      vn = dot(relative, c.normal);
      if (!(vn < c.bounce)) continue;
      const double j = (c.bounce - vn) / inverseMass;
      Vec3 change = c.normal * j;
      const Vec3 tangential = relative - c.normal * vn;
      const double slip = length(tangential);
      if (c.friction > 0.0 && slip > 0.0) change -= tangential * (std::min(c.friction * j, slip / inverseMass) / slip);
      for (int k = 0; k < 4; ++k) {
        const uint32_t i = c.vertex[k];
        const double w = this->inverseMass(i);
        if (w == 0.0 || c.weight[k] == 0.0) continue;
        v1[i] += change * (c.weight[k] * w);
      }
      applied = true;
    }
    if (!applied) break;
  }
}

void BodyContacts::markMoved() {
  for (uint32_t b : active_) bodies_[b].moved = false;
  for (uint32_t i : dirtyList_) dirty_[i] = 0;
  for (uint32_t i : touchedList_) {
    dirty_[i] = 1;
    touched_[i] = 0;
    bodies_[vertexBody_[i]].moved = true;
  }
  std::swap(dirtyList_, touchedList_);
  touchedList_.clear();
  full_ = false;
}

bool BodyContacts::resolve(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt) {
  const bool changed = resolveStep(x0, x1, v1, dt);
  last_.steps = 1;
  last_.mostContacts = last_.contacts;
  total_.add(last_);
  return changed;
}

bool BodyContacts::beginStep(const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, double dt) {
  const Model& model = *model_;
  last_ = ContactStats{};
  for (uint32_t i : contactList_) contactOf_[i] = 0;
  contactList_.clear();
  bool finite = true;
  for (uint32_t b : active_) {
    const BodyInfo& info = model.bodies[b];
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      u_[i] = u0_[i] = (x1[i] - x0[i]) / dt;
      push_[i] = Vec3{};
      changed_[i] = touched_[i] = 0;
      stopped_[i] = 0;
      finite = finite && std::isfinite(x0[i].x + x0[i].y + x0[i].z + u_[i].x + u_[i].y + u_[i].z);
    }
  }
  // A state that is no longer finite has blown up: there is no contact to resolve, and the
  // monitor (sim/monitor.h) stops the run at its next check.
  if (!finite) return false;
  for (uint32_t b : active_) bodies_[b].moved = true;
  for (uint32_t i : dirtyList_) dirty_[i] = 0;
  dirtyList_.clear(), touchedList_.clear();
  full_ = true;
  applied_.clear();
  return true;
}

void BodyContacts::markContactVertices() {
  for (const Contact& c : contacts_) {
    for (int k = 0; k < 4; ++k) {
      const uint32_t i = c.vertex[k];
      if (c.weight[k] == 0.0 || i >= vertexCount_ || contactOf_[i]) continue;
      contactOf_[i] = 1;
      contactList_.push_back(i);
    }
  }
}

bool BodyContacts::applyImpulses(const std::vector<Vec3>& x0, double dt, bool& any, bool& settled) {
  for (int pass = 0; pass < impulsePasses_ && !settled; ++pass) {
    if (!findContacts(x0, dt, contacts_, pass == 0 ? &last_.candidates : nullptr)) return false;
    ++last_.passes;
    if (pass == 0) {
      last_.contacts = contacts_.size();
      markContactVertices();
    }
    bool applied = false;
    for (const Contact& c : contacts_) {
      if (impulse(c, dt, pass == 0)) {
        applied = true;
        ++last_.impulses;
      }
    }
    any = any || applied;
    settled = !applied;
    if (applied) markMoved();
  }
  return true;
}

void BodyContacts::stopVertices(const Contact& c, std::vector<Vec3>& v1, bool& stoppedAny, bool& stoppedNow) {
  for (uint32_t i : c.vertex) {
    if (inverseMass(i) == 0.0 || stopped_[i]) continue;
    if (!stoppedAny) std::iota(group_.begin(), group_.end(), 0u);
    v1[i] += u_[i] - u0_[i] - push_[i];  // the impulses it took so far, whose other halves stay applied
    stopped_[i] = 1;
    touch(i);
    u_[i] = Vec3{};
    stoppedAny = stoppedNow = true;
    ++last_.stopped;
  }
  // The contact's stopped vertices form one group.
  uint32_t first = UINT32_MAX;
  for (uint32_t i : c.vertex) {
    if (!stopped_[i]) continue;
    if (first == UINT32_MAX)
      first = i;
    else
      group_[findRoot(group_, i)] = findRoot(group_, first);
  }
}

bool BodyContacts::failSafe(const std::vector<Vec3>& x0, std::vector<Vec3>& v1, double dt, bool& stoppedAny) {
  const auto approaching = [&](const Contact& c) { return normalSpeed(c) < -1e-9 * c.thickness / dt; };
  for (;;) {
    if (!findContacts(x0, dt, contacts_, nullptr)) return false;
    ++last_.passes;
    bool stoppedNow = false;
    for (const Contact& c : contacts_) {
      if (approaching(c)) stopVertices(c, v1, stoppedAny, stoppedNow);
    }
    if (!stoppedNow) return true;
    markMoved();
  }
}

void BodyContacts::moveChanged(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt) {
  const Model& model = *model_;
  for (uint32_t b : active_) {
    const BodyInfo& info = model.bodies[b];
    for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
      if (!changed_[i] || stopped_[i]) continue;
      x1[i] = x0[i] + u_[i] * dt;
      v1[i] += u_[i] - u0_[i] - push_[i];
    }
  }
}

void BodyContacts::shareGroupMomentum(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1) {
  const Model& model = *model_;
  for (uint32_t i = 0; i < model.vertexCount(); ++i) {
    if (stopped_[i]) groupMomentum_[findRoot(group_, i)] = Vec3{}, groupMass_[findRoot(group_, i)] = 0.0;
  }
  for (uint32_t i = 0; i < model.vertexCount(); ++i) {
    if (!stopped_[i]) continue;
    const uint32_t r = findRoot(group_, i);
    groupMomentum_[r] += v1[i] * model.mass[i];
    groupMass_[r] += model.mass[i];
  }
  for (uint32_t i = 0; i < model.vertexCount(); ++i) {
    if (!stopped_[i]) continue;
    const uint32_t r = findRoot(group_, i);
    x1[i] = x0[i];
    v1[i] = groupMomentum_[r] / groupMass_[r];
  }
}

bool BodyContacts::resolveStep(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt) {
  if (!beginStep(x0, x1, dt)) return false;
  // 1. Impulses, pass after pass, until no contact needs one.
  bool any = false, settled = false;
  if (!applyImpulses(x0, dt, any, settled)) return overflow(x0, x1, v1, dt);
  if (!any && impulsePasses_ > 0) return false;
  // 2. Fail-safe: stop every vertex still in an approaching contact, until none is left (a
  // pass that needed no impulse has none left).
  bool stoppedAny = false;
  if (!settled && !failSafe(x0, v1, dt, stoppedAny)) return overflow(x0, x1, v1, dt);
  // 3. New positions and end velocities.
  moveChanged(x0, x1, v1, dt);
  settleEndVelocities(v1);
  if (stoppedAny) shareGroupMomentum(x0, x1, v1);
  return true;
}

}  // namespace springy

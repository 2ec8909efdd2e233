// springy: contact between bodies and within a body (docs/model.md §17).
//
// After the integrator has moved every vertex from x0 (the start of the step) to x1, and the
// static colliders have had their say, this stage makes sure that no vertex passes through a
// triangle and no edge through an edge, of another body or (with self contact) of the same
// body. Each body has a thickness h (default kDefaultThicknessFactor times its mean edge length);
// two primitives are in contact when they come within h of each other along the step's
// straight-line paths (sim/contact_geometry.h: continuous, earliest contact, never missed).
//
// The response works on the paths' average velocities u = (x1 - x0) / dt, as Bridson, Fedkiw &
// Anderson 2002 ("Robust treatment of collisions, contact and friction for cloth animation",
// §6-7) do:
//  1. Impulses. Every contact found is given, in a fixed order, the impulse that stops the
//     primitives approaching each other at the contact point: relative normal speed 0, or a small
//     separating speed when they are already closer than h, or for an impact (the first pass, from
//     outside h, faster than the scene's resting speed) the restitution e times the approach
//     speed, e the larger of the two bodies' (Box2D's rule: a pair bounces if either is bouncy);
//     the impulse is shared among the corners by
//     their barycentric weights over their masses (Bridson et al. §7.1, the weights w_k /
//     sum w_k^2 / m_k); Coulomb friction takes up to mu times that impulse off the relative
//     tangential speed. Then the paths are tested again, up to kImpulsePasses times.
//  2. Fail-safe. Vertices still in an approaching contact after that stop for this step (their
//     paths end where they started, which was free of contact): the candidates are tested again
//     until no approaching contact is left. This always ends (at worst every vertex of the
//     contacts stops) and it is what guarantees that nothing crosses. The stopped vertices of
//     each group that touched (a union of contacts) share the group's mass-weighted mean velocity,
//     so that momentum is kept (the rigid impact zones of Provot 1997 and Harmon et al. 2008,
//     "Robust treatment of simultaneous collisions", without their rotation).
//  3. The new paths give the positions x1 = x0 + dt u, and each vertex's velocity at the end of
//     the step changes by the same amount as its average velocity did.
// Momentum is kept by every impulse (equal and opposite over the two primitives); kinetic energy
// never rises (an impulse stops or slows an approach; friction only takes tangential speed).
//
// Neighbours in the mesh are never tested against each other: a vertex and the faces it is a
// corner of, two edges that share a vertex; neither are pairs of a body that are closer than
// h at rest (a mesh may have nearly touching parts from the start; excluding pairs up to 2 h
// apart let the bunny's faces pass through each other, such pairs being common on a coarse,
// irregular mesh).
//
// Static triangle colliders (sim/colliders.h) take part too: their vertices cannot move (mass
// infinite, velocity 0). The colliders' own stage already keeps every vertex's path off their
// faces; what it cannot see is an edge of a body passing over an edge of a plate (a plate's rim
// entering between two vertices of a ball) or a plate's corner poking into a body's face. So
// this stage tests a body's edges against the colliders' sharp edges (border edges, and creases
// whose faces are not coplanar: across a flat edge nothing passes without a vertex crossing a
// face first) and the corners of those edges against the body's faces, with half the body's
// thickness and the collider's restitution and friction.
//
// Deterministic: the pairs are collected in sorted order and resolved one after another on one
// thread, so the result is the same bits on any thread count.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "sim/contact_bvh.h"
#include "sim/model.h"

namespace springy {

// Thickness of a body from its mean edge length, when the scene does not give it.
constexpr double kDefaultThicknessFactor = 0.1;
// Passes of impulses before the fail-safe.
constexpr int kImpulsePasses = 8;
// Candidate pairs per primitive (vertex, edge, face of the bodies that take part) beyond which a
// step's search is abandoned as an overflow: far more than any real contact has (a few per
// primitive), reached only when bodies have blown up or start packed inside each other, where
// testing them all would cost time quadratic in their size. An overflow is reported (the
// monitor stops the run), never passed over silently.
constexpr double kMaxCandidatesPerPrimitive = 64.0;
// The candidate pairs of two bodies are found with every primitive's swept box grown by this
// fraction of its body's thickness (a fat box) and kept over the steps while every vertex's swept
// box stays inside its fat box; each pass then only tests the kept pairs' tight boxes. Larger keeps
// them longer and makes each test pass over more pairs (docs/benchmarks.md, issue 16).
constexpr double kCandidateMarginFactor = 1.0;

// What the contact stage did in one step (and summed over a run by the caller).
struct ContactStats {
  uint64_t candidates = 0;    // pairs whose swept boxes overlapped (first pass)
  uint64_t contacts = 0;      // contacts found (first pass)
  uint64_t impulses = 0;      // impulses applied over all passes
  uint64_t passes = 0;        // passes of tests
  uint64_t stopped = 0;       // vertices the fail-safe stopped
  uint64_t steps = 0;         // steps (1 for one step)
  uint64_t mostContacts = 0;  // the most contacts in one step
  uint64_t overflows = 0;     // steps whose search was abandoned (kMaxCandidatesPerPrimitive)
  void add(const ContactStats& o) {
    candidates += o.candidates, contacts += o.contacts, impulses += o.impulses, passes += o.passes;
    stopped += o.stopped, steps += o.steps, mostContacts = std::max(mostContacts, o.mostContacts);
    overflows += o.overflows;
  }
};

class BodyContacts {
 public:
  // Whether a model needs this stage: two or more bodies with contact, a body with self contact,
  // or a body with contact and a triangle collider with a sharp edge.
  static bool needed(const Model& model);
  // Reads `model` (which must outlive this object and not move).
  explicit BodyContacts(const Model& model);
  // The inverse masses the impulses use (the World's, which a pin's release changes); they must
  // outlive this object.
  void setInverseMasses(const double* invMass) { invMass_ = invMass; }

  // Resolves the contacts of the step from x0 to x1 of length dt: corrects x1 and v1 in place.
  // Returns whether anything changed.
  bool resolve(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt);

  const ContactStats& lastStep() const { return last_; }
  const ContactStats& sinceStart() const { return total_; }
  // Whether vertex i had a contact (with a body, itself or a collider's edge or corner) in the
  // last step's first pass: for exports that show where bodies touch.
  bool touching(std::size_t i) const { return i < vertexCount_ && contactOf_[i] != 0; }
  // Passes of impulses before the fail-safe (kImpulsePasses; 0 leaves everything to the
  // fail-safe, which tests use to exercise it alone).
  void setImpulsePasses(int passes) { impulsePasses_ = passes; }
  double thickness(uint32_t body) const { return bodies_[body].thickness; }
  // The bodies whose search overflowed last (sinceStart().overflows > 0).
  std::array<uint32_t, 2> overflowPair() const { return overflowPair_; }

 private:
  // A contact found on the current paths: the vertices (up to 4), their weights in the relative
  // position (vertex-triangle: 1, -w0, -w1, -w2; edge-edge: 1 - a, a, -(1 - b), -b), the normal
  // and the distance at the contact.
  struct Contact {
    uint32_t vertex[4];
    double weight[4];
    Vec3 normal;
    double distance;
    double thickness;
    double friction;
    double restitution;
    // One side is a static collider: no push inside the thickness (see impulse()).
    bool still = false;
    // The normal speed the impulse aimed at, without the push (set when one is applied).
    double bounce = 0.0;
  };
  struct Body {
    double thickness = 0.0;
    double friction = 0.0;
    double restitution = 0.0;
    bool self = false;
    std::vector<std::array<uint32_t, 2>> edges;  // global vertex indices, each edge once, sorted
    // Trees over the fat boxes: the vertices' (fatBox_) and the edges' and faces' (their corners').
    Bvh vertexTree, edgeTree, faceTree;
    uint64_t fat = 0;          // which fat boxes it has (fatGeneration_ when they were made; 0: none)
    bool outside = true;       // a vertex's swept box is not inside its fat box (the kept pairs are stale)
    Box box;                   // the swept box of the whole body this pass
    bool near = false;         // near another body this pass, or self contact: its fat boxes are kept
    bool moved = true;         // its paths changed in the last pass (every body on the first)
    std::vector<PrimitivePair> restVertexFace, restEdgeEdge;  // self pairs near at rest (sorted)
  };
  // The candidate pairs of two bodies (or one with self contact, or a body and a collider) whose
  // fat boxes overlap, sorted, without excluded pairs: vertices of the first against faces of the
  // second, vertices of the second against faces of the first, edges against edges (self: the
  // vertex-face and edge-edge pairs; collider: the body's edges against its sharp edges, its
  // corners against the body's faces). Valid while both bodies have the fat boxes they were found
  // with (fatA, fatB; a collider's are 0).
  struct Candidates {
    uint64_t fatA = 0, fatB = 0;
    std::array<std::vector<PrimitivePair>, 3> lists;
  };
  // A triangle collider's sharp edges and their corners (vertex indices from vertexCount_ on).
  struct Static {
    uint32_t collider = 0;  // in model.colliders.meshes
    double friction = 0.0, restitution = 0.0;
    std::vector<std::array<uint32_t, 2>> edges;
    std::vector<uint32_t> vertices;
    Bvh vertexTree, edgeTree;  // over their boxes (no margin), built once
    Box box;
  };
  // The path of vertex i over the step (a collider's vertex stands still).
  // Adds the contact of vertex i and triangle t if their paths come within h (weights 1 and
  // minus the triangle's barycentrics; `still`: one side is a static collider).
  void addVertexFace(uint32_t i, const Triangle& t, const std::vector<Vec3>& x0, double dt, double h, double friction,
                     double restitution, bool still, std::vector<Contact>& out) const;
  Motion path(uint32_t i, const std::vector<Vec3>& x0, double dt) const {
    if (i >= vertexCount_) return {staticPosition_[i - vertexCount_], staticPosition_[i - vertexCount_]};
    return {x0[i], x0[i] + u_[i] * dt};
  }
  double inverseMass(uint32_t i) const { return i < vertexCount_ ? invMass_[i] : 0.0; }
  void addStatics();
  // Steps of the constructor. Body b takes part: its edges and its thickness.
  void addActive(uint32_t b);
  // maxCandidates_: kMaxCandidatesPerPrimitive times the primitives that take part.
  void setCandidateBudget();
  // Body b's self pairs closer than its thickness at rest, which are not contacts (a mesh may
  // start with parts that nearly touch): found once with boxes grown by the thickness, then measured.
  void findRestPairs(uint32_t b);
  // Step 4 of resolveStep(): the end velocities at the contacts that took an impulse.
  void settleEndVelocities(std::vector<Vec3>& v1);
  bool staticContacts(uint32_t b, const Static& s, Candidates& kept, const std::vector<Vec3>& x0, double dt,
                      std::vector<Contact>& out, uint64_t& candidates);
  // After a pass: which bodies' paths it changed (Body::moved), from touched_, which it clears
  // (dirty_ and dirtyList_ become the pass's).
  void markMoved();
  // Vertex i's path changed in this pass.
  void touch(uint32_t i) {
    changed_[i] = 1;
    if (!touched_[i]) touched_[i] = 1, touchedList_.push_back(i);
  }
  // Ends a step whose search overflowed: keeps the impulses applied so far, counts it.
  bool overflow(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt);
  bool resolveStep(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt);
  // Steps of resolveStep(). The step's paths' average velocities and the per-step state reset;
  // false when the state is not finite (nothing to resolve).
  bool beginStep(const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, double dt);
  // Step 1: passes of impulses until one needs none (settled) or kImpulsePasses are done; `any`:
  // an impulse was applied. False on an overflow.
  bool applyImpulses(const std::vector<Vec3>& x0, double dt, bool& any, bool& settled);
  // Marks the vertices of the first pass's contacts (touching()).
  void markContactVertices();
  // Step 2, the fail-safe: stops the vertices of approaching contacts until none is left. False
  // on an overflow; `stoppedAny`: a vertex was stopped.
  bool failSafe(const std::vector<Vec3>& x0, std::vector<Vec3>& v1, double dt, bool& stoppedAny);
  // Stops the movable vertices of contact c and joins its stopped vertices into one group.
  void stopVertices(const Contact& c, std::vector<Vec3>& v1, bool& stoppedAny, bool& stoppedNow);
  // Step 3: the changed paths' end positions and velocities (of the vertices not stopped).
  void moveChanged(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1, double dt);
  // Each group of stopped vertices keeps its momentum: they all stay where they were and take its
  // mass-weighted mean end velocity (the integrator's, plus the impulses taken before stopping).
  // Sums in vertex order, per group root.
  void shareGroupMomentum(const std::vector<Vec3>& x0, std::vector<Vec3>& x1, std::vector<Vec3>& v1);
  // An edge's or face's swept box this pass: its corners' merged (sweptBox() computes it so, the
  // same bits).
  Box edgeBox(const std::array<uint32_t, 2>& e) const { return merged(vertexBox_[e[0]], vertexBox_[e[1]]); }
  Box faceBox(const Triangle& t) const { return merged(merged(vertexBox_[t[0]], vertexBox_[t[1]]), vertexBox_[t[2]]); }
  // New fat boxes around the body's current swept boxes, and its trees over them.
  void refreshFat(uint32_t body);
  // Drops the kept pairs if they are too many to keep (kept.lists past maxCandidates_).
  void trimKept(Candidates& kept) const;
  // Every contact on the current paths, in a fixed order; false on an overflow (out incomplete).
  bool findContacts(const std::vector<Vec3>& x0, double dt, std::vector<Contact>& out, uint64_t* candidates);
  // Steps of findContacts(). The swept boxes of the vertices with new paths and of their bodies.
  void sweepBodies(const std::vector<Vec3>& x0, double dt);
  // Which bodies are near another, a collider or themselves (Body::near); new fat boxes for those
  // whose vertices left theirs.
  void markNearBodies();
  // The kept candidates at kept_[index], made when first needed.
  Candidates& keptAt(std::size_t index) {
    if (!kept_[index]) kept_[index] = std::make_unique<Candidates>();
    return *kept_[index];
  }
  bool pairContacts(uint32_t a, uint32_t b, Candidates& kept, const std::vector<Vec3>& x0, double dt,
                    std::vector<Contact>& out, uint64_t& candidates);
  // The contact's relative normal speed on the current paths.
  double normalSpeed(const Contact& c) const;
  // Counts the pairs just collected (pairs_); whether the search is still within
  // kMaxCandidatesPerPrimitive per primitive.
  bool withinBudget(uint64_t& candidates) const {
    candidates += pairs_.size();
    return static_cast<double>(candidates) <= maxCandidates_;
  }
  // Applies the contact's impulse to u; true if one was needed. `impact`: the first pass, where
  // an approach faster than the resting speed rebounds by the restitution.
  bool impulse(const Contact& c, double dt, bool impact);

  const Model* model_;
  const double* invMass_;  // the World's (setInverseMasses), the model's until set
  std::vector<Body> bodies_;
  std::vector<uint32_t> active_;  // bodies that take part, in order
  std::vector<Static> statics_;
  uint32_t vertexCount_ = 0;          // the model's; collider vertices follow
  std::vector<Vec3> staticPosition_;  // collider vertices
  // Per vertex (the model's, then the colliders'): the path's average velocity, now and as integrated.
  std::vector<Vec3> u_, u0_;
  std::vector<Vec3> push_;  // the part of u_ - u0_ that moves positions only (kSeparationRate)
  std::vector<uint8_t> changed_, stopped_;
  std::vector<uint8_t> touched_;  // changed in the current pass (per vertex)
  std::vector<uint8_t> contactOf_;        // per vertex: in a contact of the last step (touching())
  std::vector<uint32_t> contactList_;     // the vertices contactOf_ marks
  std::vector<uint8_t> dirty_;    // changed in the pass before (per vertex; collider vertices never)
  std::vector<uint32_t> touchedList_, dirtyList_;  // the vertices with touched_, dirty_ set
  std::vector<uint32_t> vertexBody_;               // per vertex of an active body: the body
  bool full_ = true;                               // this pass tests every candidate pair (the first of a step)
  // Per vertex of the bodies: the swept box this pass (half the thickness around the path), and
  // the fat box the kept candidates were found with.
  std::vector<Box> vertexBox_, fatBox_;
  uint64_t fatGeneration_ = 0;  // fat boxes made so far
  // Kept candidates per pair of active_ positions (k, l), k <= l, at k * n + l, then per (k, collider
  // s) at n * n + k * statics + s; empty when the bodies are not near (dropped on a step's first pass).
  std::vector<std::unique_ptr<Candidates>> kept_;
  bool dirtyEdge(const std::array<uint32_t, 2>& e) const { return dirty_[e[0]] || dirty_[e[1]]; }
  bool dirtyCorner(const Triangle& t) const { return dirty_[t[0]] || dirty_[t[1]] || dirty_[t[2]]; }
  std::vector<Box> boxes_;
  std::vector<PrimitivePair> pairs_;
  std::vector<Contact> contacts_;
  std::vector<Contact> applied_;  // the contacts that took an impulse this step, in order
  std::vector<uint32_t> group_;  // union-find over the stopped vertices
  std::vector<Vec3> groupMomentum_;  // per group root: the stopped vertices' momentum and mass
  std::vector<double> groupMass_;
  ContactStats last_, total_;
  int impulsePasses_ = kImpulsePasses;
  double maxCandidates_ = 0.0;
  std::array<uint32_t, 2> overflowPair_{0, 0};  // per search: kMaxCandidatesPerPrimitive x the primitives
};

}  // namespace springy

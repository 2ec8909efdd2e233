// springy: a refittable bounding volume hierarchy for the broad phase of body-body and self
// contact (issue 16).
//
// Soft bodies deform but never change topology, so the tree over a body's primitives (vertices,
// edges or faces, as swept boxes from contact_geometry.h) is built once and then refitted each
// step: the same nodes over the same primitives, bounds recomputed bottom-up in O(N). Refitting
// keeps the queries exact (every node still bounds its primitives) but lets the tree loosen as
// the body deforms; degradation() measures that and needsRebuild() flags it past a factor (2 by
// default: a heuristic for when a rebuild pays for itself, not a measured optimum). The build is
// a median split on the longest axis of the centroid bounds, like TriangleCollider::buildBvh
// (sim/colliders.cpp), and deterministic: ties are broken by primitive index.
//
// Queries report pairs of primitives whose boxes overlap, appended to a caller-owned vector that
// grows (nothing is dropped), sorted by (a, b) so that the order does not depend on the tree's
// shape: before and after a rebuild, on every run, the same pairs come in the same order. The
// traversal keeps an explicit stack on the heap, so a deep tree cannot overflow the call stack.
//
// Cost: build O(N log N); refit O(N); a query visits node pairs whose boxes overlap. For
// well-separated geometry (each box overlaps O(1) others, boxes of comparable size, so a node's
// box overlaps O(1) nodes of its own size) that is O(N + K) for K reported pairs, plus
// O(K log K) to sort them; boxes that all overlap each other make it O(N^2), as the output is.
#pragma once

#include <compare>
#include <cstdint>
#include <span>
#include <vector>

#include "sim/contact_geometry.h"

namespace springy {

// Two primitives whose boxes overlap: indices into the boxes the trees were built from.
struct PrimitivePair {
  uint32_t a = 0, b = 0;
  auto operator<=>(const PrimitivePair&) const = default;
};

class Bvh {
 public:
  static constexpr uint32_t kLeafSize = 4;  // most primitives in a leaf

  // Nodes in depth-first order: an inner node's children are at index + 1 and `right`; a leaf
  // holds the slots [first, first + count) of the leaf order.
  struct Node {
    Box box;
    uint32_t first = 0, count = 0;  // leaf range (count > 0 for leaves)
    uint32_t right = 0;             // right child (inner nodes)
    bool leaf() const { return count > 0; }
  };

  // Builds the tree over boxes[0 .. N).
  void build(std::span<const Box> boxes);
  // New boxes for the same N primitives (same indices): updates every node's bounds bottom-up.
  // (A different count is a programmer error: asserted, and in release builds a full build.)
  void refit(std::span<const Box> boxes);
  // Builds a fresh tree over the current (last refitted) boxes.
  void rebuild();
  // How much looser the tree is than right after the last build: (sum of the inner nodes' surface
  // areas / the root's) now over the same at the build; 1 after a build. Relative to the root so
  // that moving or uniformly scaling a body does not count, only nodes that spread over each
  // other as the body deforms (the expected number of inner nodes a query visits grows with it).
  double degradation() const;
  bool needsRebuild(double factor = 2.0) const { return degradation() > factor; }

  uint32_t primitiveCount() const { return static_cast<uint32_t>(primitive_.size()); }
  const std::vector<Node>& nodes() const { return nodes_; }
  uint32_t primitiveAt(uint32_t slot) const { return primitive_[slot]; }  // primitive in leaf slot
  const Box& boxAt(uint32_t slot) const { return box_[slot]; }            // its box
  const Box& boxOf(uint32_t primitive) const { return box_[slot_[primitive]]; }  // a primitive's box
  // A new box for one primitive; the nodes above it are stale until refitNodes().
  void setBox(uint32_t primitive, const Box& box) { box_[slot_[primitive]] = box; }
  // Updates every node's bounds bottom-up from the primitives' boxes.
  void refitNodes();
  // Appends every primitive whose box overlaps `box`, in the tree's leaf order.
  void query(const Box& box, std::vector<uint32_t>& out) const;

 private:
  double quality() const;  // sum of inner node surface areas / the root's

  std::vector<Node> nodes_;
  std::vector<uint32_t> primitive_;  // leaf order -> primitive index
  std::vector<uint32_t> slot_;       // primitive index -> leaf order
  std::vector<Box> box_;             // primitive boxes in leaf order
  double builtQuality_ = 0.0;
};

// Appends every pair (a in `a`, b in `b`) whose boxes overlap, in (a, b) order.
void overlapPairs(const Bvh& a, const Bvh& b, std::vector<PrimitivePair>& out);
// The same, without the pairs for which exclude(a, b) is true (e.g. a vertex and the faces it
// is a corner of, when both trees hold one body).
template <class Exclude>
void overlapPairs(const Bvh& a, const Bvh& b, const Exclude& exclude, std::vector<PrimitivePair>& out);

// Appends every unordered pair of different primitives of one tree whose boxes overlap, once,
// as (a, b) with a < b, sorted.
void selfOverlapPairs(const Bvh& tree, std::vector<PrimitivePair>& out);
// The same, without the pairs for which exclude(a, b) is true (a < b), e.g. two edges that share
// a vertex.
template <class Exclude>
void selfOverlapPairs(const Bvh& tree, const Exclude& exclude, std::vector<PrimitivePair>& out);

// Implementation: one traversal each, with the filter passed as a function pointer and context
// (no filter: null), so that the traversal is compiled once.
namespace detail {
using PairFilter = bool (*)(const void* context, uint32_t a, uint32_t b);  // true: drop the pair
void overlapPairs(const Bvh& a, const Bvh& b, PairFilter exclude, const void* context, std::vector<PrimitivePair>& out);
void selfOverlapPairs(const Bvh& tree, PairFilter exclude, const void* context, std::vector<PrimitivePair>& out);
}  // namespace detail

template <class Exclude>
void overlapPairs(const Bvh& a, const Bvh& b, const Exclude& exclude, std::vector<PrimitivePair>& out) {
  detail::overlapPairs(
      a, b, [](const void* c, uint32_t i, uint32_t j) -> bool { return (*static_cast<const Exclude*>(c))(i, j); },
      &exclude, out);
}

template <class Exclude>
void selfOverlapPairs(const Bvh& tree, const Exclude& exclude, std::vector<PrimitivePair>& out) {
  detail::selfOverlapPairs(
      tree, [](const void* c, uint32_t i, uint32_t j) -> bool { return (*static_cast<const Exclude*>(c))(i, j); },
      &exclude, out);
}

}  // namespace springy

#include "sim/contact_bvh.h"

#include <algorithm>
#include <cassert>
#include <limits>
#include <utility>

namespace springy {

void Bvh::build(std::span<const Box> boxes) {
  assert(boxes.size() < std::numeric_limits<uint32_t>::max());
  const uint32_t n = static_cast<uint32_t>(boxes.size());
  primitive_.resize(n);
  std::vector<Vec3> centroid(n);
  for (uint32_t i = 0; i < n; ++i) {
    primitive_[i] = i;
    centroid[i] = (boxes[i].lo + boxes[i].hi) * 0.5;
  }
  nodes_.clear();
  if (n > 0) nodes_.reserve(2 * ((n + kLeafSize - 1) / kLeafSize));
  // Depth first with an explicit stack: a task becomes the next node, its left child is built
  // right after it (index + 1) and its right child when the left subtree is done, which then
  // patches `right` into its parent.
  struct Task {
    uint32_t first, count, parent;  // parent: node whose `right` this is, or none
  };
  constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  std::vector<Task> stack;
  if (n > 0) stack.push_back({0, n, kNone});
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    const uint32_t index = static_cast<uint32_t>(nodes_.size());
    nodes_.push_back({});
    if (task.parent != kNone) nodes_[task.parent].right = index;
    if (task.count <= kLeafSize) {
      nodes_[index].first = task.first;
      nodes_[index].count = task.count;
      continue;
    }
    // Median split on the longest axis of the centroids' bounds; ties (equal centroids, or all
    // centroids equal) broken by primitive index, so the tree does not depend on input order
    // beyond the indices and the split always halves the range.
    Vec3 lo = centroid[primitive_[task.first]], hi = lo;
    for (uint32_t k = task.first + 1; k < task.first + task.count; ++k) {
      lo = componentMin(lo, centroid[primitive_[k]]);
      hi = componentMax(hi, centroid[primitive_[k]]);
    }
    const Vec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const uint32_t half = task.count / 2;
    const auto begin = primitive_.begin() + task.first;
    std::nth_element(begin, begin + half, begin + task.count, [&](uint32_t u, uint32_t w) {
      const double cu = centroid[u][axis], cw = centroid[w][axis];
      return cu < cw || (cu == cw && u < w);
    });
    stack.push_back({task.first + half, task.count - half, index});
    stack.push_back({task.first, half, kNone});
  }
  box_.resize(n);
  for (uint32_t k = 0; k < n; ++k) box_[k] = boxes[primitive_[k]];
  slot_.resize(n);
  for (uint32_t k = 0; k < n; ++k) slot_[primitive_[k]] = k;
  refitNodes();
  builtQuality_ = quality();
}

void Bvh::refit(std::span<const Box> boxes) {
  assert(boxes.size() == primitive_.size());
  if (boxes.size() != primitive_.size()) {  // not the same primitives: only a new tree is exact
    build(boxes);
    return;
  }
  for (std::size_t k = 0; k < primitive_.size(); ++k) box_[k] = boxes[primitive_[k]];
  refitNodes();
}

void Bvh::rebuild() {
  std::vector<Box> boxes(box_.size());
  for (std::size_t k = 0; k < box_.size(); ++k) boxes[primitive_[k]] = box_[k];
  build(boxes);
}

// Children come after their parent in depth-first order, so one sweep from the back sees every
// child before its parent.
void Bvh::refitNodes() {
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    Node& node = nodes_[i];
    if (node.leaf()) {
      Box box = box_[node.first];
      for (uint32_t k = node.first + 1; k < node.first + node.count; ++k) box = merged(box, box_[k]);
      node.box = box;
    } else {
      node.box = merged(nodes_[i + 1].box, nodes_[node.right].box);
    }
  }
}

double Bvh::quality() const {
  if (nodes_.empty()) return 0.0;
  const double root = surfaceArea(nodes_[0].box);
  if (!(root > 0.0)) return 0.0;  // all boxes on one line or point: nothing to compare
  double inner = 0.0;
  for (const Node& node : nodes_) {
    if (!node.leaf()) inner += surfaceArea(node.box);
  }
  return inner / root;
}

double Bvh::degradation() const {
  const double now = quality();
  if (builtQuality_ > 0.0) return now / builtQuality_;
  return now > 0.0 ? std::numeric_limits<double>::infinity() : 1.0;
}

void Bvh::query(const Box& box, std::vector<uint32_t>& out) const {
  if (nodes_.empty()) return;
  thread_local std::vector<uint32_t> stack;
  stack.clear();
  stack.push_back(0);
  while (!stack.empty()) {
    const uint32_t i = stack.back();
    stack.pop_back();
    const Node& node = nodes_[i];
    if (!overlaps(node.box, box)) continue;
    if (node.leaf()) {
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        if (overlaps(box_[k], box)) out.push_back(primitive_[k]);
      }
    } else {
      stack.push_back(node.right);
      stack.push_back(i + 1);
    }
  }
}

namespace detail {

namespace {

using NodePair = std::pair<uint32_t, uint32_t>;

// Every slot pair of two leaves whose boxes overlap. `self`: both leaves belong to one tree, so
// pairs are ordered (smaller index first); `same`: it is one leaf, so each pair once, no slot
// with itself.
void leafPairs(const Bvh& ta, const Bvh::Node& la, const Bvh& tb, const Bvh::Node& lb, bool self, bool same,
               PairFilter exclude, const void* context, std::vector<PrimitivePair>& out) {
  for (uint32_t i = la.first; i < la.first + la.count; ++i) {
    for (uint32_t j = same ? i + 1 : lb.first; j < lb.first + lb.count; ++j) {
      if (!overlaps(ta.boxAt(i), tb.boxAt(j))) continue;
      uint32_t a = ta.primitiveAt(i), b = tb.primitiveAt(j);
      if (self && b < a) std::swap(a, b);
      if (exclude && exclude(context, a, b)) continue;
      out.push_back({a, b});
    }
  }
}

// Descend into the node with the larger box (the one more likely to be split usefully), unless
// it is a leaf. Deterministic: ties go to the first.
bool descendFirst(const Bvh::Node& a, const Bvh::Node& b) {
  if (a.leaf()) return false;
  if (b.leaf()) return true;
  return surfaceArea(a.box) >= surfaceArea(b.box);
}

// Node pairs (i in ta, j in tb) with overlapping boxes, down to leaf pairs. For one tree (self)
// the caller only pushes pairs of disjoint subtrees.
void traverse(const Bvh& ta, const Bvh& tb, bool self, std::vector<NodePair>& stack, PairFilter exclude,
              const void* context, std::vector<PrimitivePair>& out) {
  const auto& na = ta.nodes();
  const auto& nb = tb.nodes();
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (self && i == j) {
      // One subtree against itself: both children against themselves and each other.
      const Bvh::Node& node = na[i];
      if (node.leaf()) {
        leafPairs(ta, node, ta, node, true, true, exclude, context, out);
        continue;
      }
      const uint32_t left = i + 1, right = node.right;
      stack.push_back({right, right});
      stack.push_back({left, left});
      if (overlaps(na[left].box, na[right].box)) stack.push_back({left, right});
      continue;
    }
    const Bvh::Node& a = na[i];
    const Bvh::Node& b = nb[j];
    if (a.leaf() && b.leaf()) {
      leafPairs(ta, a, tb, b, self, false, exclude, context, out);
    } else if (descendFirst(a, b)) {
      if (overlaps(na[a.right].box, b.box)) stack.push_back({a.right, j});
      if (overlaps(na[i + 1].box, b.box)) stack.push_back({i + 1, j});
    } else {
      if (overlaps(a.box, nb[b.right].box)) stack.push_back({i, b.right});
      if (overlaps(a.box, nb[j + 1].box)) stack.push_back({i, j + 1});
    }
  }
}

}  // namespace

namespace {

// Both queries: the traversal from the roots, then this query's pairs sorted. The stack is kept
// per thread and reused, so a query in a time step allocates nothing once it has grown.
void collectPairs(const Bvh& a, const Bvh& b, bool self, PairFilter exclude, const void* context,
                  std::vector<PrimitivePair>& out) {
  if (a.nodes().empty() || b.nodes().empty()) return;
  if (!self && !overlaps(a.nodes()[0].box, b.nodes()[0].box)) return;
  thread_local std::vector<NodePair> stack;
  stack.clear();
  const std::size_t start = out.size();
  stack.push_back({0, 0});
  traverse(a, b, self, stack, exclude, context, out);
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(start), out.end());
}

}  // namespace

void overlapPairs(const Bvh& a, const Bvh& b, PairFilter exclude, const void* context,
                  std::vector<PrimitivePair>& out) {
  collectPairs(a, b, false, exclude, context, out);
}

void selfOverlapPairs(const Bvh& tree, PairFilter exclude, const void* context, std::vector<PrimitivePair>& out) {
  collectPairs(tree, tree, true, exclude, context, out);
}

}  // namespace detail

void overlapPairs(const Bvh& a, const Bvh& b, std::vector<PrimitivePair>& out) {
  detail::overlapPairs(a, b, nullptr, nullptr, out);
}

void selfOverlapPairs(const Bvh& tree, std::vector<PrimitivePair>& out) {
  detail::selfOverlapPairs(tree, nullptr, nullptr, out);
}

}  // namespace springy

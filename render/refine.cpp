#include "render/refine.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace springy::render {

int PnRefinement::levelFor(std::size_t triangles) {
  if (triangles == 0) return 0;
  const double n = std::floor(std::sqrt(static_cast<double>(kTargetTriangles) / static_cast<double>(triangles)));
  return n < 2.0 ? 0 : static_cast<int>(std::min(n, 3.0));
}

PnRefinement::PnRefinement(std::span<const std::uint32_t> triangles, std::size_t vertexCount, int level)
    : level_(level), coarseVertices_(vertexCount), coarse_(triangles.begin(), triangles.end()) {
  if (level_ < 2) {
    level_ = 0;
    return;
  }
  const std::uint32_t n = static_cast<std::uint32_t>(level_);
  std::unordered_map<std::uint64_t, std::uint32_t> edgeIds;
  auto edgeOf = [&](std::uint32_t a, std::uint32_t b) {
    const std::uint32_t lo = std::min(a, b), hi = std::max(a, b);
    const auto [it, added] =
        edgeIds.try_emplace(std::uint64_t{lo} << 32 | hi, static_cast<std::uint32_t>(edges_.size()));
    if (added) edges_.push_back({lo, hi});
    return it->second;
  };
  const std::size_t faces = coarse_.size() / 3;
  for (std::size_t f = 0; f < faces; ++f) {
    edgeOf(coarse_[3 * f], coarse_[3 * f + 1]);
    edgeOf(coarse_[3 * f + 1], coarse_[3 * f + 2]);
    edgeOf(coarse_[3 * f + 2], coarse_[3 * f]);
  }
  const std::size_t perEdge = n - 1, perFace = (n - 1) * (n - 2) / 2;
  const std::size_t firstFacePoint = coarseVertices_ + edges_.size() * perEdge;
  vertexCount_ = firstFacePoint + faces * perFace;
  // Lattice point (j, k) of face f: weights j of its second corner, k of its third, n - j - k of
  // its first.
  std::vector<std::uint32_t> lattice((n + 1) * (n + 1));
  for (std::size_t f = 0; f < faces; ++f) {
    const std::uint32_t c[3] = {coarse_[3 * f], coarse_[3 * f + 1], coarse_[3 * f + 2]};
    std::uint32_t interior = 0;
    for (std::uint32_t j = 0; j <= n; ++j)
      for (std::uint32_t k = 0; j + k <= n; ++k) {
        const std::uint32_t w[3] = {n - j - k, j, k};
        std::uint32_t index;
        if (w[0] == n || w[1] == n || w[2] == n) {
          index = c[w[0] == n ? 0 : w[1] == n ? 1 : 2];
        } else if (w[0] == 0 || w[1] == 0 || w[2] == 0) {
          // On the edge between the two corners with weight: point s of the edge counted from its
          // lower vertex = the weight of its higher one.
          const int x = w[0] == 0 ? 1 : 0, y = w[2] == 0 ? 1 : 2;
          const std::uint32_t e = edgeOf(c[x], c[y]);
          const std::uint32_t s = c[x] > c[y] ? w[x] : w[y];
          index = static_cast<std::uint32_t>(coarseVertices_ + e * perEdge + (s - 1));
        } else {
          index = static_cast<std::uint32_t>(firstFacePoint + f * perFace + interior++);
        }
        lattice[j * (n + 1) + k] = index;
      }
    auto at = [&](std::uint32_t j, std::uint32_t k) { return lattice[j * (n + 1) + k]; };
    for (std::uint32_t j = 0; j < n; ++j)
      for (std::uint32_t k = 0; j + k < n; ++k) {
        triangles_.insert(triangles_.end(), {at(j, k), at(j + 1, k), at(j, k + 1)});
        if (j + k + 2 <= n) triangles_.insert(triangles_.end(), {at(j + 1, k), at(j + 1, k + 1), at(j, k + 1)});
      }
  }
}

void PnRefinement::evaluate(std::span<const glm::vec3> P, std::span<const glm::vec3> N,
                            std::vector<glm::vec3>& out, std::span<const std::uint8_t> flat) const {
  out.resize(vertexCount_);
  std::copy(P.begin(), P.begin() + static_cast<std::ptrdiff_t>(coarseVertices_), out.begin());
  const int n = level_;
  const float inv = 1.0f / static_cast<float>(n);
  // The control point next to corner a on edge a-b (Vlachos et al. 2001, eq. for b210):
  // (2 Pa + Pb - ((Pb - Pa) . Na) Na) / 3; on the chord, (2 Pa + Pb) / 3, at a flat vertex. An
  // edge's curve still depends on its two vertices alone: no cracks either way. Every corner of a
  // triangle at a flat vertex is made flat too: a free neighbour's patch would bulge toward the
  // wall the flat vertex rests on (seen: ball colours dotting the outside of the stack's tray).
  std::vector<std::uint8_t>& flatter = flatter_;
  flatter.clear();
  if (!flat.empty()) {
    flatter.assign(flat.begin(), flat.end());
    for (std::size_t t = 0; t + 2 < coarse_.size(); t += 3) {
      const std::uint32_t a = coarse_[t], b = coarse_[t + 1], c = coarse_[t + 2];
      if (flat[a] != 0 || flat[b] != 0 || flat[c] != 0) flatter[a] = flatter[b] = flatter[c] = 1;
    }
  }
  auto tangent = [&](std::uint32_t a, std::uint32_t b) {
    const float bend = flatter.empty() || flatter[a] == 0 ? glm::dot(P[b] - P[a], N[a]) : 0.0f;
    return (2.0f * P[a] + P[b] - bend * N[a]) * (1.0f / 3.0f);
  };
  std::size_t o = coarseVertices_;
  for (const auto& [a, b] : edges_) {
    const glm::vec3 b0 = P[a], b1 = tangent(a, b), b2 = tangent(b, a), b3 = P[b];
    for (int s = 1; s < n; ++s) {
      const float t = static_cast<float>(s) * inv, u = 1.0f - t;
      out[o++] = u * u * u * b0 + 3.0f * u * u * t * b1 + 3.0f * u * t * t * b2 + t * t * t * b3;
    }
  }
  const std::size_t faces = coarse_.size() / 3;
  for (std::size_t f = 0; f < faces && n >= 3; ++f) {
    const std::uint32_t i1 = coarse_[3 * f], i2 = coarse_[3 * f + 1], i3 = coarse_[3 * f + 2];
    const glm::vec3 b300 = P[i1], b030 = P[i2], b003 = P[i3];
    const glm::vec3 b210 = tangent(i1, i2), b120 = tangent(i2, i1), b021 = tangent(i2, i3);
    const glm::vec3 b012 = tangent(i3, i2), b102 = tangent(i3, i1), b201 = tangent(i1, i3);
    const glm::vec3 e = (b210 + b120 + b021 + b012 + b102 + b201) * (1.0f / 6.0f);
    const glm::vec3 v = (b300 + b030 + b003) * (1.0f / 3.0f);
    const glm::vec3 b111 = e + 0.5f * (e - v);
    // Interior lattice points in the constructor's order (j outer, k inner, both >= 1).
    for (int j = 1; j < n; ++j)
      for (int k = 1; j + k < n; ++k) {
        const float uu = static_cast<float>(j) * inv, vv = static_cast<float>(k) * inv, ww = 1.0f - uu - vv;
        out[o++] = b300 * ww * ww * ww + b030 * uu * uu * uu + b003 * vv * vv * vv +
                   3.0f * (b210 * ww * ww * uu + b120 * ww * uu * uu + b201 * ww * ww * vv + b021 * uu * uu * vv +
                           b102 * ww * vv * vv + b012 * uu * vv * vv) +
                   6.0f * b111 * ww * uu * vv;
      }
  }
}

}  // namespace springy::render

// The one translation unit that includes CGAL (heavy, header-only, GPL-3.0-or-later packages):
// keep it that way, so that only this file pays CGAL's compile time and -frounding-math.
#include "mesh/proxy.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sim/error.h"
#include "mesh/mesh_io.h"

namespace springy {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using FaceIndex = SurfaceMesh::Face_index;
using VertexIndex = SurfaceMesh::Vertex_index;

// CGAL's remeshing splits edges longer than 4/3 of its target and collapses those shorter than
// 4/5; the mean edge it leaves is 0.90-0.94 of the target (measured on spheres, a bunny and
// wraps of open and non-manifold input), so it is asked for a little more than the target.
constexpr double kRemeshTargetScale = 1.08;

// How many times the wrap is redone with a doubled offset when the remeshed wrap intersects
// itself.
constexpr int kMaxOffsetRetries = 3;

// A target edge that would give a proxy of more vertices than this (estimated from the input's
// area) is refused rather than left to run out of time or memory.
constexpr double kMaxVertexEstimate = 5e6;

// Area of a closed equilateral-triangle mesh of V vertices and edge L: about 2V triangles of
// sqrt(3)/4 L^2 each, so L = sqrt(2 area / (sqrt(3) V)).
double edgeForVertices(double area, std::size_t vertices) {
  return std::sqrt(2.0 * area / (std::sqrt(3.0) * static_cast<double>(vertices)));
}

double triangleArea(const std::vector<Vec3>& p, const Triangle& t) {
  return 0.5 * length(cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]));
}

std::string formatNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

// Union-find over vertex indices (for counting pieces).
class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), uint32_t{0}); }
  uint32_t find(uint32_t i) {
    while (parent_[i] != i) {
      parent_[i] = parent_[parent_[i]];
      i = parent_[i];
    }
    return i;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<uint32_t> parent_;
};

// What is wrong with the input, in a few words for the summary: "closed" or a list such as
// "open, non-manifold, 3 pieces" or "inside out", after merging exactly coincident vertices.
std::string describeInput(const TriMesh& input) {
  const TriMesh welded = weldVertices(input, 0.0);
  if (welded.triangles.empty()) return "degenerate";
  std::vector<std::pair<uint64_t, int>> edges;  // (undirected key, +1 for lo->hi, -1 for hi->lo)
  edges.reserve(3 * welded.triangles.size());
  UnionFind pieces(welded.positions.size());
  for (const Triangle& t : welded.triangles) {
    for (std::size_t k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      const uint64_t key = (uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      edges.emplace_back(key, a < b ? 1 : -1);
      pieces.unite(a, b);
    }
  }
  std::sort(edges.begin(), edges.end());
  bool open = false, nonManifold = false, flipped = false;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 1) open = true;
    if (j - i > 2) nonManifold = true;
    if (j - i == 2 && edges[i].second == edges[i + 1].second) flipped = true;
    i = j;
  }
  std::size_t pieceCount = 0;
  for (uint32_t v = 0; v < welded.positions.size(); ++v) {
    if (pieces.find(v) == v) ++pieceCount;
  }
  std::string text;
  auto add = [&text](const std::string& word) { text += (text.empty() ? "" : ", ") + word; };
  if (open) add("open");
  if (nonManifold) add("non-manifold");
  if (flipped) add("inconsistently oriented");
  if (pieceCount > 1) add(std::to_string(pieceCount) + " pieces");
  if (text.empty() && signedVolume(welded.positions, welded.triangles) < 0.0) add("inside out");
  return text.empty() ? "closed" : text;
}

// Keeps the connected component of largest area (the lowest index among equal areas) and
// returns how many were dropped.
std::size_t keepLargestPiece(SurfaceMesh& mesh) {
  auto faceComponent = mesh.add_property_map<FaceIndex, std::size_t>("f:component", 0).first;
  const std::size_t count = PMP::connected_components(mesh, faceComponent);
  if (count <= 1) {
    mesh.remove_property_map(faceComponent);
    return 0;
  }
  std::vector<double> area(count, 0.0);
  for (FaceIndex f : mesh.faces()) area[faceComponent[f]] += PMP::face_area(f, mesh);
  const auto largest = static_cast<std::size_t>(std::max_element(area.begin(), area.end()) - area.begin());
  PMP::keep_connected_components(mesh, std::vector<std::size_t>{largest}, faceComponent);
  mesh.remove_property_map(faceComponent);
  mesh.collect_garbage();
  return count - 1;
}

TriMesh toTriMesh(const SurfaceMesh& mesh) {
  TriMesh out;
  out.positions.reserve(mesh.number_of_vertices());
  for (VertexIndex v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    out.positions.push_back({p.x(), p.y(), p.z()});
  }
  out.triangles.reserve(mesh.number_of_faces());
  for (FaceIndex f : mesh.faces()) {
    Triangle t{};
    std::size_t k = 0;
    for (VertexIndex v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      if (k == 3) throw Error("proxy: the remeshed wrap has a face with more than 3 corners");
      t[k++] = static_cast<uint32_t>(v.idx());
    }
    if (k != 3) throw Error("proxy: the remeshed wrap has a face with fewer than 3 corners");
    out.triangles.push_back(t);
  }
  return out;
}

// Stops PMP::self_intersections at the first pair it reports.
struct FirstPairFound {
  std::size_t a, b;
};
struct ThrowOnFirstPair {
  using iterator_category = std::output_iterator_tag;
  using value_type = void;
  using difference_type = std::ptrdiff_t;
  using pointer = void;
  using reference = void;
  ThrowOnFirstPair& operator*() { return *this; }
  ThrowOnFirstPair& operator++() { return *this; }
  ThrowOnFirstPair operator++(int) { return *this; }
  ThrowOnFirstPair& operator=(const std::pair<FaceIndex, FaceIndex>& pair) {
    throw FirstPairFound{std::min(pair.first.idx(), pair.second.idx()),
                         std::max(pair.first.idx(), pair.second.idx())};
  }
};


// Step of buildProxy: options it can work with: a finite target edge (or 0 with a vertex
// count), positive alpha and offset, iterations not negative.
void checkProxyOptions(const ProxyOptions& options) {
  if (!(options.targetEdge >= 0.0) || !std::isfinite(options.targetEdge)) {
    throw Error("proxy: the target edge length must be a finite positive number, or 0 to use a vertex count");
  }
  if (options.targetEdge == 0.0 && options.targetVertices == 0) {
    throw Error("proxy: give a target edge length or a target vertex count");
  }
  if (!(options.alpha > 0.0) || !(options.offset > 0.0) || options.remeshIterations < 0) {
    throw Error("proxy: alpha and offset must be positive and the remeshing iterations not negative");
  }
}

// Step of buildProxy: the input's area [mesh units^2], from finite vertices and indices in range;
// an input without any is refused.
double checkedInputArea(const TriMesh& input) {
  const std::size_t vertexCount = input.positions.size();
  for (std::size_t i = 0; i < vertexCount; ++i) {
    if (!isFinite(input.positions[i])) {
      throw Error("proxy: vertex " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
  double inputArea = 0.0;
  for (std::size_t t = 0; t < input.triangles.size(); ++t) {
    for (uint32_t v : input.triangles[t]) {
      if (v >= vertexCount) {
        throw Error("proxy: triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                    ", but the mesh has only " + std::to_string(vertexCount) + " vertices");
      }
    }
    inputArea += triangleArea(input.positions, input.triangles[t]);
  }
  if (!(inputArea > 0.0)) throw Error("proxy: the mesh has no triangle with area");
  return inputArea;
}

// Step of buildProxy: wraps the input (alpha and offset in `result`), keeps the largest piece and
// remeshes it to the target edge. A part of the input thinner than the edge (a sheet, a fin, a
// needle) is wrapped as a shell 2 x offset thick, which remeshing at the target edge can fold
// through itself: then the wrap is redone with the offset doubled, up to kMaxOffsetRetries times.
void wrapAndRemesh(const TriMesh& input, const ProxyOptions& options, ProxyResult& result) {
  std::vector<Point> points;
  points.reserve(input.positions.size());
  for (const Vec3& p : input.positions) points.emplace_back(p.x, p.y, p.z);
  std::vector<std::array<std::size_t, 3>> soup;
  soup.reserve(input.triangles.size());
  for (const Triangle& t : input.triangles) soup.push_back({t[0], t[1], t[2]});
  for (int attempt = 0;; ++attempt) {
    SurfaceMesh mesh;
    CGAL::alpha_wrap_3(points, soup, result.alpha, result.offset, mesh);
    if (mesh.is_empty()) throw Error("proxy: alpha wrapping produced no surface");
    result.droppedPieces = keepLargestPiece(mesh);
    result.edge = options.targetEdge > 0.0 ? options.targetEdge
                                           : edgeForVertices(PMP::area(mesh), options.targetVertices);
    PMP::isotropic_remeshing(
        mesh.faces(), kRemeshTargetScale * result.edge, mesh,
        CGAL::parameters::number_of_iterations(static_cast<unsigned>(options.remeshIterations)));
    mesh.collect_garbage();
    result.selfIntersecting = PMP::does_self_intersect(mesh);
    if (!result.selfIntersecting || attempt == kMaxOffsetRetries) {
      result.mesh = toTriMesh(mesh);
      return;
    }
    result.offset *= 2.0;
  }
}

// Step of buildProxy: the summary line, with what was dropped or raised (`scale`: the wrap's
// scale, which the offset option is relative to).
std::string proxySummary(const TriMesh& input, const ProxyOptions& options, double scale, const ProxyResult& result) {
  std::string summary = "wrapped " + std::to_string(input.triangles.size()) + " triangles (" + describeInput(input) +
                        ") into a closed proxy of " + std::to_string(result.mesh.positions.size()) +
                        " vertices, edge " + formatNumber(result.edge);
  if (result.droppedPieces > 0) {
    summary += "; kept the largest of " + std::to_string(result.droppedPieces + 1) +
               " separate wraps (parts farther apart than alpha " + formatNumber(result.alpha) + ")";
  }
  if (result.offset > options.offset * scale) {
    summary += "; offset raised to " + formatNumber(result.offset) + " (parts thinner than the edge)";
  }
  if (result.selfIntersecting) summary += "; self-intersecting (parts thinner than the edge)";
  return summary;
}

}  // namespace

ProxyResult buildProxy(const TriMesh& input, const ProxyOptions& options) {
  checkProxyOptions(options);
  const double inputArea = checkedInputArea(input);
  // The wrap's scale: the target edge, or first a guess from the input's area (which counts
  // both sides of an open sheet once, and overlaps twice: the final edge comes from the wrap).
  const double scale = options.targetEdge > 0.0 ? options.targetEdge
                                                : edgeForVertices(inputArea, options.targetVertices);
  const double vertexEstimate = options.targetEdge > 0.0 ? 2.0 * inputArea / (std::sqrt(3.0) * scale * scale)
                                                         : static_cast<double>(options.targetVertices);
  if (vertexEstimate > kMaxVertexEstimate) {
    throw Error("proxy: a proxy of about " + formatNumber(vertexEstimate) + " vertices is too many (at most " +
                formatNumber(kMaxVertexEstimate) + "): give a longer target edge or fewer vertices");
  }
  ProxyResult result;
  result.alpha = options.alpha * scale;
  result.offset = options.offset * scale;
  wrapAndRemesh(input, options, result);
  if (auto problem = findManifoldProblem(result.mesh)) throw Error("proxy: the result is not usable: " + *problem);
  const double volume = signedVolume(result.mesh.positions, result.mesh.triangles);
  if (!(volume > 0.0)) throw Error("proxy: the result encloses no volume");
  result.summary = proxySummary(input, options, scale, result);
  return result;
}

std::optional<std::string> needsProxy(const TriMesh& mesh, std::size_t maxVertices) {
  if (auto problem = findManifoldProblem(mesh)) return problem;
  const std::vector<Vec3>& p = mesh.positions;
  if (maxVertices > 0 && p.size() > maxVertices) {
    return std::to_string(p.size()) + " vertices, more than " + std::to_string(maxVertices);
  }

  {
    SurfaceMesh sm;
    sm.reserve(static_cast<SurfaceMesh::size_type>(p.size()), 0,
               static_cast<SurfaceMesh::size_type>(mesh.triangles.size()));
    for (const Vec3& v : p) sm.add_vertex(Point(v.x, v.y, v.z));
    for (const Triangle& t : mesh.triangles) {
      // A closed manifold (checked above) adds every face; face i is triangle i.
      if (sm.add_face(VertexIndex(t[0]), VertexIndex(t[1]), VertexIndex(t[2])) == SurfaceMesh::null_face()) {
        return "triangle " + std::to_string(sm.number_of_faces()) + " cannot be added to a manifold surface";
      }
    }
    try {
      PMP::self_intersections(sm, ThrowOnFirstPair{});
    } catch (const FirstPairFound& pair) {
      return "self-intersecting (triangles " + std::to_string(pair.a) + " and " + std::to_string(pair.b) + ")";
    }
  }

  std::vector<int> valence(p.size(), 0);
  for (const Triangle& t : mesh.triangles) {
    for (uint32_t v : t) ++valence[v];
  }
  const auto maxValence = std::max_element(valence.begin(), valence.end());
  if (*maxValence > kProxyMaxValence) {
    return "max valence " + std::to_string(*maxValence) + " (vertex " +
           std::to_string(maxValence - valence.begin()) + ")";
  }

  double minAngle = kPi;
  std::size_t minAngleTriangle = 0;
  double minEdge = std::numeric_limits<double>::infinity(), maxEdge = 0.0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Triangle& t = mesh.triangles[i];
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec3 a = p[t[(k + 1) % 3]] - p[t[k]];
      const Vec3 b = p[t[(k + 2) % 3]] - p[t[k]];
      const double angle = std::atan2(length(cross(a, b)), dot(a, b));
      if (angle < minAngle) {
        minAngle = angle;
        minAngleTriangle = i;
      }
      minEdge = std::min(minEdge, length(a));
      maxEdge = std::max(maxEdge, length(a));
    }
  }
  const double minDegrees = minAngle * 180.0 / kPi;
  if (minDegrees < kProxyMinAngleDegrees) {
    return "min angle " + formatNumber(minDegrees) + " deg (triangle " + std::to_string(minAngleTriangle) + ")";
  }
  if (maxEdge > kProxyMaxEdgeRatio * minEdge) {
    return "edge lengths differ by " + formatNumber(maxEdge / minEdge) + "x (" + formatNumber(minEdge) + " to " +
           formatNumber(maxEdge) + ")";
  }
  return std::nullopt;
}

}  // namespace springy

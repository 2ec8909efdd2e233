// springy: a simulation proxy, for meshes that cannot or should not be simulated as they are.
//
// A soft body must be one closed, outward-oriented 2-manifold (mesh/mesh_io.h), and it simulates
// best with near-equilateral triangles of even size: a sliver's hinge is ill-conditioned, and
// high-valence poles and uneven edges spread mass and stiffness unevenly. A user's mesh that is
// open, in pieces, non-manifold, self-intersecting, badly shaped or far finer than needed can
// instead be simulated through a proxy: a new closed, outward, manifold surface of well-shaped
// triangles that wraps it, at a chosen edge length.
//
// The proxy is built with CGAL 5.5: 3D Alpha Wrapping (CGAL::alpha_wrap_3, which takes any
// triangle soup: holes, pieces, overlaps, flipped or duplicated faces) gives a closed, manifold,
// intersection-free surface strictly outside the input, then isotropic remeshing
// (CGAL::Polygon_mesh_processing::isotropic_remeshing) makes its triangles near-equilateral at
// the target edge length. CGAL's Alpha_wrap_3 and Polygon_mesh_processing packages are
// GPL-3.0-or-later (see LICENSE). All CGAL code lives in mesh/proxy.cpp.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "sim/mesh.h"

namespace springy {

struct ProxyOptions {
  // The proxy's mean edge length [mesh units] (it comes out within about 2%). When 0, the edge is
  // chosen so that the proxy has about `targetVertices` vertices (from the area of the alpha
  // wrap; within about 5%). One of the two must be positive.
  double targetEdge = 0.0;
  std::size_t targetVertices = 0;
  // Alpha wrapping, both relative to the target edge. `alpha` is the radius of the empty ball
  // that carves the space around the input: holes, gaps and concavities narrower than about it
  // are closed over (a round hole of radius below alpha, two parts closer than alpha join), finer
  // detail is smoothed away; parts farther apart than it wrap separately. `offset` is the
  // distance of the wrap outside the input: the proxy is that much fatter (a sphere of radius r
  // gains about 3 offset / r of its volume, 0.4% at 20 edges across); smaller offsets make the
  // wrap slower.
  double alpha = 2.5;
  double offset = 0.05;
  // Isotropic remeshing: passes of split, collapse, flip, tangential smoothing and projection
  // back onto the wrap.
  int remeshIterations = 5;
};

struct ProxyResult {
  TriMesh mesh;         // closed, outward, one piece; passes findManifoldProblem
  double edge = 0.0;    // the target edge length used [mesh units]
  double alpha = 0.0;   // the alpha and (final) offset used [mesh units]
  double offset = 0.0;
  std::size_t droppedPieces = 0;  // separate wraps dropped (only the largest is kept)
  // The proxy intersects itself even at the largest offset tried (see buildProxy); a proxy
  // of an input without parts thinner than the edge never does.
  bool selfIntersecting = false;
  // One line for the user, e.g. "wrapped 5096 triangles (open) into a closed proxy of 1429
  // vertices, edge 0.1", with what was dropped or raised.
  std::string summary;
};

// Builds the proxy of `input`, which may be any triangle soup: open, in pieces, non-manifold,
// self-intersecting, inconsistently oriented or inside out (indices must be in range,
// coordinates finite). Steps: alpha wrap; if the wrap falls apart into several closed pieces
// (parts of the input farther apart than alpha), keep the one of largest area and say so;
// remesh isotropically to the target edge; if the result intersects itself (parts of the input
// thinner than the edge, such as a sheet or a fin, are wrapped as a shell only 2 x offset thick
// that the remeshing can fold through), redo it all with the offset doubled, up to 3 times.
// Deterministic: the same input and options give the same output, bit for bit. Throws
// springy::Error when the input is unusable (no triangle with area, a non-finite coordinate,
// an index out of range, no target given) or, which should not happen, the result fails
// findManifoldProblem or encloses no volume.
ProxyResult buildProxy(const TriMesh& input, const ProxyOptions& options);

// Why `mesh` should be simulated through a proxy, or nothing when it is fine as it is: a short
// reason. In order: findManifoldProblem's description (open, non-manifold, flipped faces,
// pieces, zero-area triangles), more than `maxVertices` vertices (0: no limit),
// "self-intersecting (triangles 3 and 17)", "max valence 64 (vertex 0)", "min angle 0.5 deg
// (triangle 12)", "edge lengths differ by 25x".
std::optional<std::string> needsProxy(const TriMesh& mesh, std::size_t maxVertices);

// The thresholds needsProxy applies.
inline constexpr int kProxyMaxValence = 12;
inline constexpr double kProxyMinAngleDegrees = 10.0;
inline constexpr double kProxyMaxEdgeRatio = 10.0;

}  // namespace springy

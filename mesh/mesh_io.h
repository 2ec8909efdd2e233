// springy: loading triangle meshes from files, welding, validation and simplification.
//
// A soft body must be one closed, consistently oriented 2-manifold: every edge shared by exactly
// two triangles that traverse it in opposite directions, one connected piece, no degenerate
// triangle. Files from the wild rarely arrive that way (split vertices at UV seams, duplicated
// corners), so loading welds coincident vertices first, then validates, and a mesh that still
// fails is rejected with the file and the first offending edge or vertex.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "sim/mesh.h"

namespace springy {

// Reads every triangle of every mesh in a file assimp understands (OBJ, PLY, STL, glTF, ...),
// triangulating polygons, with node transforms applied (a mirroring transform keeps the winding
// outward). Points and lines are ignored. Throws springy::Error naming the file when it cannot be
// read, holds no triangles or has a non-finite coordinate. No welding or validation here.
TriMesh readMeshFile(const std::string& path);

// Merges vertices closer than `tolerance` (absolute, in the mesh's units), remaps the triangles
// and drops triangles that collapse (two equal corners) and unused vertices. Merging is
// transitive (a chain of close vertices becomes one). Deterministic: the result depends only on
// the input, never on hash-table iteration order. Surviving vertices keep their relative input
// order, each merged vertex the exact position of its lowest-index member, so an already welded
// mesh comes back unchanged. tolerance <= 0 merges exactly equal positions only.
TriMesh weldVertices(const TriMesh& mesh, double tolerance);

// Returns nothing when `mesh` is a single closed, consistently oriented 2-manifold with no
// zero-area triangle and no unused vertex; otherwise a one-line description of the first problem
// found, naming the vertex indices, edge or triangle, e.g.
//   "edge (12, 40) belongs to 1 triangle: the mesh has a hole"
//   "edge (3, 7) is shared by 3 triangles: non-manifold edge"
//   "edge (5, 9) is traversed twice in the same direction (triangles 4 and 17): flipped face"
//   "the mesh has 2 separate pieces (vertex 0 and vertex 8 are not connected)"
//   "triangle 6 (2, 2, 5) has zero area"
//   "vertex 5 joins 2 separate fans of triangles: non-manifold vertex"
// Checks run in this order: non-finite coordinate, index out of range, zero area (below 1e-12 x
// bounding-box diagonal squared, or repeated corner), unused vertex, non-manifold edge, hole,
// flipped face, non-manifold vertex, separate pieces. Self-intersection is not checked.
//
// Surface::Open (a cloth) allows border edges (an edge of one triangle) and asks the rest: a
// single consistently oriented 2-manifold with boundary, each edge in one or two triangles (two
// traversing it in opposite directions), each vertex's triangles one fan (a disc, or a half disc
// on the border; two fans meeting at a vertex is "non-manifold vertex"), one piece.
enum class Surface { Closed, Open };
std::optional<std::string> findManifoldProblem(const TriMesh& mesh, Surface surface = Surface::Closed);

// A vertex far away from the rest (an edge over a million times longer than the median edge):
// one such vertex sets the bounding box that welding and the zero-area test measure against, and
// makes every other triangle look degenerate. Returns a description naming it, or nothing.
std::optional<std::string> findStrayVertex(const TriMesh& mesh);

// Orientation: if the closed mesh encloses negative volume (inside-out), flips every triangle.
// Returns true if it flipped.
bool orientOutward(TriMesh& mesh);

// readMeshFile + findStrayVertex + weldVertices(tolerance relative to the bounding-box diagonal).
// Throws springy::Error "PATH: <problem>".
TriMesh readWeldedMesh(const std::string& path, double relativeWeldTolerance = 1e-6);

// Validation (findManifoldProblem) + orientOutward + a positive enclosed volume, on a welded
// mesh read from `path`. Throws springy::Error "PATH: <problem>" when it is not usable as a body.
void finishClosedMesh(TriMesh& mesh, const std::string& path);

// Validation as an open surface (findManifoldProblem with Surface::Open), for a mesh simulated
// as cloth as it is: its orientation is kept (an open surface has no outside). Throws
// springy::Error "PATH: <problem>" naming the bad edge, vertex or triangle.
void finishClothMesh(const TriMesh& mesh, const std::string& path);

// readWeldedMesh + finishClosedMesh.
TriMesh loadClosedMesh(const std::string& path, double relativeWeldTolerance = 1e-6);

// Simplifies a closed mesh to about `targetVertices` vertices with meshoptimizer, keeping it a
// closed manifold (validated afterwards; throws springy::Error if simplification broke it). The
// input must pass findManifoldProblem (springy::Error otherwise). Returns the input unchanged
// when targetVertices is not below its vertex count; meshoptimizer may stop above the target if
// topology forbids further collapses. Surviving vertices keep their original double positions
// and relative order.
TriMesh simplifyMesh(const TriMesh& mesh, std::size_t targetVertices);

}  // namespace springy

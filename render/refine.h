// Why: a soft body is simulated on a mesh as coarse as its physics allows (146 vertices for a
// ball), and drawn flat that shows its facets on the outline. Refinement draws it from a finer
// surface bound to the simulation mesh each frame: PN triangles (Vlachos, Peters, Boyd and
// Mitchell, "Curved PN Triangles", I3D 2001), a cubic Bezier patch per triangle built from its
// corners and their normals only. The patch passes through every simulated vertex (a body
// resting on the ground still touches it) and two patches sharing an edge share its curve (it
// depends on that edge's two vertices and normals only), so the surface has no cracks. The
// simulation is untouched. Internal to render/.
#pragma once
#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

namespace springy::render {

class PnRefinement {
 public:
  PnRefinement() = default;
  // level n >= 2: each triangle becomes n * n triangles (shared vertices on shared edges).
  PnRefinement(std::span<const std::uint32_t> triangles, std::size_t vertexCount, int level);
  bool active() const { return level_ >= 2; }
  int level() const { return level_; }
  std::size_t vertexCount() const { return vertexCount_; }
  const std::vector<std::uint32_t>& triangles() const { return triangles_; }
  // positions / normals of the coarse mesh (3 floats per vertex, unit normals); out gets
  // 3 * vertexCount() floats: the refined positions. `flat` (empty, or one per coarse vertex):
  // nonzero keeps the surface flat at that vertex and its neighbours (their edges' control points
  // on the chords), for a vertex resting on a collider: a patch bulging there would cross a thin
  // wall it lies on.
  void evaluate(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                std::vector<glm::vec3>& out, std::span<const std::uint8_t> flat = {}) const;

  // Only coarse meshes are refined (a fine one shows no facets on its outline and would cost
  // for nothing): the level for a mesh of `triangles` triangles puts it at about
  // kTargetTriangles after refinement, at most 3 (a 146-vertex ball's outline is smooth at 3):
  // 3 up to 1333 triangles, 2 up to 3000, none above.
  static constexpr std::size_t kTargetTriangles = 12000;
  static int levelFor(std::size_t triangles);

 private:
  int level_ = 0;
  std::size_t coarseVertices_ = 0, vertexCount_ = 0;
  std::vector<std::uint32_t> coarse_;                // 3 per coarse triangle
  std::vector<std::array<std::uint32_t, 2>> edges_;  // a < b
  std::vector<std::uint32_t> triangles_;             // refined
  // evaluate's scratch (the vertices kept flat), kept between frames: not allocated per frame.
  // evaluate is const but not for concurrent use on one object.
  mutable std::vector<std::uint8_t> flatter_;
};

}  // namespace springy::render

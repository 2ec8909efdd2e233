// Why: props (a gallows' post and bar, crates, balls) need simple closed meshes without an
// asset pipeline. Builders return plain arrays ready for Renderer::addStaticMesh. Faces that
// should look flat (box sides, cylinder caps) get their own vertices, so the renderer's smooth
// area-weighted normals stay sharp at those edges. Triangles wind counter-clockwise seen from
// outside.
#pragma once
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace springy::render {

struct MeshData {
  std::vector<float> positions;        // x, y, z per vertex
  std::vector<std::uint32_t> indices;  // 3 per triangle
  std::size_t vertexCount() const { return positions.size() / 3; }
};

// Axis-aligned box (24 vertices, 12 triangles).
MeshData makeBox(glm::vec3 centre, glm::vec3 halfExtents);
// Closed cylinder whose axis runs from a to b.
MeshData makeCylinder(glm::vec3 a, glm::vec3 b, float radius, int segments = 32);
// UV sphere.
MeshData makeSphere(glm::vec3 centre, float radius, int rings = 16, int segments = 32);
// Appends `more` to `into` (re-indexing), e.g. to make one gallows mesh from a post and a bar.
void appendMesh(MeshData& into, const MeshData& more);

}  // namespace springy::render

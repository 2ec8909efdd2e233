#include "render/mesh_builders.h"

#include <cmath>
#include <glm/gtc/constants.hpp>

namespace springy::render {

namespace {
std::uint32_t addVertex(MeshData& m, glm::vec3 p) {
  const auto index = static_cast<std::uint32_t>(m.vertexCount());
  m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
  return index;
}
void addTriangle(MeshData& m, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  m.indices.insert(m.indices.end(), {a, b, c});
}
}  // namespace

MeshData makeBox(glm::vec3 c, glm::vec3 h) {
  MeshData m;
  // For each face: outward normal axis n and two tangents u, v with u x v = n.
  const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int axis = 0; axis < 3; ++axis) {
    for (float sign : {1.0f, -1.0f}) {
      const glm::vec3 n = axes[axis] * sign;
      const glm::vec3 u = axes[(axis + 1) % 3] * sign;
      const glm::vec3 v = axes[(axis + 2) % 3];
      const std::uint32_t first = static_cast<std::uint32_t>(m.vertexCount());
      for (glm::vec2 q : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)})
        addVertex(m, c + h * (n + q.x * u + q.y * v));
      addTriangle(m, first, first + 1, first + 2);
      addTriangle(m, first, first + 2, first + 3);
    }
  }
  return m;
}

MeshData makeCylinder(glm::vec3 a, glm::vec3 b, float radius, int segments) {
  MeshData m;
  if (segments < 3) segments = 3;
  const glm::vec3 axis = glm::normalize(b - a);
  const glm::vec3 helper = std::abs(axis.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 u = glm::normalize(glm::cross(helper, axis));
  const glm::vec3 v = glm::cross(axis, u);  // (u, v, axis) right-handed
  const auto seg = static_cast<std::uint32_t>(segments);
  auto ring = [&](glm::vec3 base, std::uint32_t i) {
    const float t = glm::two_pi<float>() * static_cast<float>(i) / static_cast<float>(seg);
    return base + radius * (std::cos(t) * u + std::sin(t) * v);
  };
  // Side: shared vertices around each ring (smooth).
  const std::uint32_t side = static_cast<std::uint32_t>(m.vertexCount());
  for (std::uint32_t i = 0; i < seg; ++i) {
    addVertex(m, ring(a, i));
    addVertex(m, ring(b, i));
  }
  for (std::uint32_t i = 0; i < seg; ++i) {
    const std::uint32_t j = (i + 1) % seg;
    const std::uint32_t a0 = side + 2 * i, b0 = a0 + 1, a1 = side + 2 * j, b1 = a1 + 1;
    addTriangle(m, a0, a1, b1);
    addTriangle(m, a0, b1, b0);
  }
  // Caps: own vertices (flat).
  for (int end = 0; end < 2; ++end) {
    const glm::vec3 base = end == 0 ? a : b;
    const std::uint32_t centre = addVertex(m, base);
    for (std::uint32_t i = 0; i < seg; ++i) addVertex(m, ring(base, i));
    for (std::uint32_t i = 0; i < seg; ++i) {
      const std::uint32_t p = centre + 1 + i, q = centre + 1 + (i + 1) % seg;
      if (end == 0) addTriangle(m, centre, q, p);  // faces -axis
      else addTriangle(m, centre, p, q);           // faces +axis
    }
  }
  return m;
}

MeshData makeSphere(glm::vec3 c, float radius, int rings, int segments) {
  MeshData m;
  if (rings < 2) rings = 2;
  if (segments < 3) segments = 3;
  const auto R = static_cast<std::uint32_t>(rings), S = static_cast<std::uint32_t>(segments);
  for (std::uint32_t r = 0; r <= R; ++r) {
    const float phi = glm::pi<float>() * static_cast<float>(r) / static_cast<float>(R);
    for (std::uint32_t s = 0; s <= S; ++s) {
      const float theta = glm::two_pi<float>() * static_cast<float>(s) / static_cast<float>(S);
      addVertex(m, c + radius * glm::vec3(std::sin(phi) * std::cos(theta), std::cos(phi),
                                          -std::sin(phi) * std::sin(theta)));
    }
  }
  for (std::uint32_t r = 0; r < R; ++r) {
    for (std::uint32_t s = 0; s < S; ++s) {
      const std::uint32_t i0 = r * (S + 1) + s, i1 = i0 + 1, j0 = i0 + S + 1, j1 = j0 + 1;
      if (r != 0) addTriangle(m, i0, j0, i1);
      if (r + 1 != R) addTriangle(m, i1, j0, j1);
    }
  }
  return m;
}

void appendMesh(MeshData& into, const MeshData& more) {
  const auto offset = static_cast<std::uint32_t>(into.vertexCount());
  into.positions.insert(into.positions.end(), more.positions.begin(), more.positions.end());
  for (std::uint32_t i : more.indices) into.indices.push_back(i + offset);
}

}  // namespace springy::render

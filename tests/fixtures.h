// Small hand-built worlds for the physics tests.
#pragma once

#include <cmath>
#include <vector>

#include "sim/model.h"
#include "sim/world.h"

namespace springy::test {

// One free vertex of the given mass, no colliders.
inline Model vertexModel(const Vec3& position, const Vec3& velocity, const Vec3& gravity, double mass = 1.0) {
  Model model;
  model.gravity = gravity;
  model.mass = {mass};
  model.invMass = {1.0 / mass};
  model.restPosition = {position};
  model.initialVelocity = {velocity};
  model.body = {0};
  BodyInfo info;
  info.name = "vertex";
  info.vertexCount = 1;
  info.mass = mass;
  model.bodies = {info};
  return model;
}

// Two vertices joined by one strut along x, no gravity, no colliders.
inline Model strutModel(double m0, double m1, double restLength, double k, double d, bool pinFirst) {
  Model model;
  model.gravity = {};
  model.mass = {m0, m1};
  model.invMass = {pinFirst ? 0.0 : 1.0 / m0, 1.0 / m1};
  model.restPosition = {{0, 0, 0}, {restLength, 0, 0}};
  model.initialVelocity = {{}, {}};
  model.body = {0, 0};
  model.struts = {{0, 1, restLength, k, d}};
  BodyInfo info;
  info.name = "strut";
  info.vertexCount = 2;
  info.strutCount = 1;
  info.mass = m0 + m1;
  model.bodies = {info};
  if (pinFirst) model.pinned = {0};
  return model;
}

// Two triangles (0, 1, 2) and (1, 0, 3) sharing the edge 0-1 along x, folded to `angle`
// (the signed dihedral angle), unit masses, one hinge, optionally the five struts.
inline std::vector<Vec3> hingePositions(double angle) {
  // Left wing in the y > 0 half-plane tilted down by angle/2, right wing mirrored: the
  // dihedral angle of this pair is `angle` (positive = convex, normals along +z when flat).
  const double a = angle / 2;
  return {{0, 0, 0}, {1, 0, 0}, {0.4, std::cos(a), -std::sin(a)}, {0.6, -std::cos(a), -std::sin(a)}};
}

inline Model hingeModel(double restAngle, double k, double d, bool withStruts, double strutK = 0.0,
                         double strutD = 0.0) {
  Model model;
  model.gravity = {};
  model.mass = {1, 1, 1, 1};
  model.invMass = {1, 1, 1, 1};
  model.restPosition = hingePositions(restAngle);
  model.initialVelocity = std::vector<Vec3>(4);
  model.body = {0, 0, 0, 0};
  model.faces = {{0, 1, 2}, {1, 0, 3}};
  model.hinges = {{{0, 1, 2, 3}, restAngle, k, d}};
  if (withStruts) {
    const auto& p = model.restPosition;
    for (auto [i, j] : std::vector<std::pair<uint32_t, uint32_t>>{{0, 1}, {0, 2}, {1, 2}, {0, 3}, {1, 3}}) {
      model.struts.push_back({i, j, length(p[j] - p[i]), strutK, strutD});
    }
  }
  BodyInfo info;
  info.name = "hinge";
  info.vertexCount = 4;
  info.strutCount = static_cast<uint32_t>(model.struts.size());
  info.hingeCount = 1;
  info.faceCount = 2;
  info.mass = 4;
  model.bodies = {info};
  return model;
}

}  // namespace springy::test

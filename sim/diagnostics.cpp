#include "sim/diagnostics.h"

#include <cmath>
#include <cstring>

#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/strut.h"

namespace springy {

BodyMeasures measureBody(const World& world, uint32_t body) {
  const Model& model = world.model();
  const BodyInfo& info = model.bodies[body];
  const std::vector<Vec3>& x = world.positions();
  const std::vector<Vec3>& v = world.velocities();
  BodyMeasures m;
  double totalMass = 0.0, speedSquared = 0.0;
  Bounds b = {x[info.firstVertex], x[info.firstVertex]};
  for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i) {
    const double mi = model.mass[i];
    m.finite = m.finite && isFinite(x[i]) && isFinite(v[i]);
    totalMass += mi;
    m.centroid += x[i] * mi;
    m.momentum += v[i] * mi;
    m.angularMomentum += cross(x[i], v[i]) * mi;
    m.kinetic += 0.5 * mi * lengthSquared(v[i]);
    m.gravitational -= mi * dot(model.gravity, x[i]);
    speedSquared += lengthSquared(v[i]);
    b.lo = componentMin(b.lo, x[i]);
    b.hi = componentMax(b.hi, x[i]);
    m.penetration = std::fmax(m.penetration, model.colliders.planePenetration(x[i]));
  }
  m.centroid = m.centroid / totalMass;
  m.rmsSpeed = std::sqrt(speedSquared / info.vertexCount);
  m.size = length(b.size());
  m.elastic = strutEnergy(model.struts.data(), info.firstStrut, info.firstStrut + info.strutCount, x.data()) +
              hingeEnergy(model.hinges.data(), info.firstHinge, info.firstHinge + info.hingeCount, x.data());
  for (uint32_t s = info.firstStrut; s < info.firstStrut + info.strutCount; ++s) {
    const Strut& st = model.struts[s];
    m.maxStrain = std::fmax(m.maxStrain, std::fabs(length(x[st.j] - x[st.i]) - st.restLength) / st.restLength);
  }
  m.volume = enclosedVolume(model, body, x.data());
  m.elastic += gasEnergy(info, m.volume);
  return m;
}

uint64_t stateHash(const World& world) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&](const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) {
      h ^= p[k];
      h *= 1099511628211ull;
    }
  };
  mix(world.positions().data(), world.positions().size() * sizeof(Vec3));
  mix(world.velocities().data(), world.velocities().size() * sizeof(Vec3));
  const double t = world.time();
  mix(&t, sizeof t);
  return h;
}

}  // namespace springy

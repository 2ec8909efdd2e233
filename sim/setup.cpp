#include "sim/setup.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sim/error.h"
#include "sim/intersections.h"
#include "sim/mesh.h"
#include "sim/stability.h"

namespace springy {

Model buildModel(const SimulationDesc& scene) {
  Model model;
  model.gravity = scene.gravity;
  model.drag = scene.drag;
  if (scene.wind) {
    Wind w = *scene.wind;
    // Gust phases and frequency spread from a splitmix64 sequence of the seed: the same seed
    // gives the same gusts on every platform (no std:: distribution involved).
    uint64_t state = w.seed;
    auto next = [&state] {
      uint64_t z = (state += 0x9E3779B97F4A7C15ull);
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    };
    for (int i = 0; i < 4; ++i) {
      w.phase[i] = 2 * kPi * next();
      w.frequency[i] = (0.5 + next()) / w.gustPeriod * (1.0 + 0.37 * i);
    }
    model.wind = w;
  }
  for (const BodyDesc& b : scene.bodies) {
    try {
      addBody(model, b);
    } catch (const Error& e) {
      throw Error((b.source.empty() ? scene.path : b.source) + ": " + e.what());
    }
  }
  // A body that starts inside a plane's solid is pushed out violently on the first step (the
  // monitor then reports energy rising from nothing): say where instead.
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    const BodyDesc& body = scene.bodies[b];
    const double size = length(boundsOf(body.mesh.positions).size());
    for (std::size_t p = 0; p < scene.planes.size(); ++p) {
      const PlaneCollider& plane = scene.planes[p];
      for (std::size_t v = 0; v < body.mesh.positions.size(); ++v) {
        const double depth = -dot(body.mesh.positions[v] - plane.point, plane.normal);
        if (depth > 1e-9 * size) {
          std::ostringstream text;
          text << body.source << ": body '" << body.name << "' starts inside [[plane]] #" << p + 1 << ": its vertex "
               << v << " is " << depth << " m behind the plane; move the body (position) to the plane's open side";
          throw Error(text.str());
        }
      }
    }
  }
  // Bodies that take part in contact and start crossing each other (or themselves, with self
  // contact) cannot be sorted out by the contact stage, which keeps things from crossing but
  // does not uncross them: say which instead.
  const std::vector<Intersection> crossing = findIntersections(model, model.restPosition, 1);
  if (!crossing.empty()) {
    const Intersection& c = crossing[0];
    const BodyInfo &a = model.bodies[c.bodyA], &b = model.bodies[c.bodyB];
    const BodyDesc& desc = scene.bodies[c.bodyA];
    std::ostringstream text;
    text << (desc.source.empty() ? scene.path : desc.source) << ": body '" << a.name << "' starts ";
    if (c.bodyA == c.bodyB) {
      text << "crossing itself (self_contact): its faces " << c.faceA - a.firstFace << " and " << c.faceB - a.firstFace;
    } else {
      text << "crossing body '" << b.name << "': its face " << c.faceA - a.firstFace << " and face "
           << c.faceB - b.firstFace << " of '" << b.name << "'";
    }
    text << " cross at (" << c.point.x << ", " << c.point.y << ", " << c.point.z << "); move the bodies apart"
         << (c.bodyA == c.bodyB ? ", or set self_contact = false" : ", or set contact = false on one of them");
    throw Error(text.str());
  }
  model.colliders.planes = scene.planes;
  model.colliders.meshes = scene.triangleColliders;
  // Impacts slower than a few steps' worth of gravity are resting contact, not bounces: a
  // vertex on the ground gains |g| dt of speed per step and must not be launched back up.
  const double dt = stepSize(scene);
  model.colliders.restingSpeed = scene.restingSpeed >= 0.0 ? scene.restingSpeed : 4.0 * length(scene.gravity) * dt;
  return model;
}

double impactMargin(const SimulationDesc& desc) {
  const bool element = std::any_of(desc.bodies.begin(), desc.bodies.end(),
                                   [](const BodyDesc& d) { return d.material == MaterialModel::Element; });
  return element ? kImpactMarginElement : kImpactMargin;
}

double adviseSubsteps(SimulationDesc& desc) {
  const Model model = buildModel(desc);
  const StabilityReport r = estimateStability(model, model.restPosition, desc.integrator, desc.duration);
  if (std::isfinite(r.dtMax) && r.dtMax > 0.0) desc.substeps = safeSubsteps(desc.dt, r.dtMax, impactMargin(desc));
  return r.dtMax;
}

}  // namespace springy

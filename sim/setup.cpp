#include "sim/setup.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sim/error.h"
#include "sim/intersections.h"
#include "sim/mesh.h"
#include "sim/stability.h"

namespace springy {

namespace {

// An [[attach]] table in the model: a hard one as a pin track that carries the vertices with the
// collider's motion, a soft one as springs (Model::Attachment).
void addAttachment(Model& model, const AttachDesc& a, const SimulationDesc& scene) {
  const BodyInfo& info = model.bodies[a.body];
  std::vector<uint32_t> vertices;
  for (uint32_t v : a.vertices) vertices.push_back(info.modelVertex[v]);
  if (a.period <= 0.0) {  // hard: to a collider only (the scene refuses a hard one to a body)
    const TriangleCollider& c = scene.triangleColliders[static_cast<std::size_t>(a.toCollider)];
    Model::PinTrack track{a.body, c.motion, a.release, vertices};
    for (std::size_t k = 0; k < vertices.size(); ++k) {
      const uint32_t v = vertices[k];
      if (model.invMass[v] == 0.0) {
        throw Error(a.where + ": vertex " + std::to_string(a.vertices[k]) + " of body '" + info.name +
                    "' is pinned already; a vertex is held by one thing");
      }
      model.invMass[v] = 0.0;
      model.initialVelocity[v] = c.motion.velocityAt(model.restPosition[v], 0.0);
      model.pinned.push_back(v);
    }
    std::sort(model.pinned.begin(), model.pinned.end());
    model.pinned.erase(std::unique(model.pinned.begin(), model.pinned.end()), model.pinned.end());
    model.pinTracks.push_back(std::move(track));
    return;
  }
  // The spring's period is that of the two ends on their own: k = mu omega^2 with mu the
  // reduced mass of the pair (the vertex's mass against a collider), and its damping makes the
  // amplitude decay as exp(-t / decay): d = 2 mu / decay.
  const double omega = 2.0 * kPi / a.period;
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    Model::Attachment s;
    s.vertex = vertices[k];
    double m = model.mass[s.vertex];
    Vec3 end;
    if (a.toBody >= 0) {
      s.other = model.bodies[static_cast<std::size_t>(a.toBody)].modelVertex[a.targets[k]];
      m = m * model.mass[s.other] / (m + model.mass[s.other]);  // the pair's reduced mass
      end = model.restPosition[s.other];
    } else {
      s.collider = static_cast<uint32_t>(a.toCollider);
      const Movement& motion = scene.triangleColliders[s.collider].motion;
      // The point of the collider where the vertex is at the start, in the collider's rest frame.
      s.anchor = motion.moves() ? motion.pose(0.0).inverse(model.restPosition[s.vertex]) : model.restPosition[s.vertex];
      end = model.restPosition[s.vertex];
    }
    s.rest = length(end - model.restPosition[s.vertex]);
    s.k = m * omega * omega;
    s.d = 2.0 * m / a.decay;
    s.release = a.release;
    model.attachments.push_back(s);
  }
}

}  // namespace

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
  for (TriangleCollider& tc : model.colliders.meshes) tc.buildBvh();  // the model is complete: its trees built
  for (const AttachDesc& a : scene.attachments) addAttachment(model, a, scene);
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

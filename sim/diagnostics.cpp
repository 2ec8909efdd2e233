#include "sim/diagnostics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/strut.h"

namespace springy {

namespace {

// measureBody splits a body into regions of this many vertices (with the elements whose first
// vertex lies in them), measures the regions on the world's threads and combines their sums in
// region order: the same numbers on every thread count.
constexpr uint32_t kRegionVertices = 512;

struct RegionSums {
  double mass = 0.0, speedSquared = 0.0, kinetic = 0.0, gravitational = 0.0, elastic = 0.0;
  double maxStrain = 0.0, penetration = 0.0;
  Vec3 centroid, momentum, angularMomentum, lo, hi;
  bool finite = true;
};

// The first index in [lo, hi) whose key is at least `bound`, for keys ascending over [lo, hi)
// (addBody sorts a body's elements by their first vertex). Starting each search at the last
// boundary keeps the regions a partition of the elements even if they were not sorted.
template <class Key>
uint32_t firstAtLeast(uint32_t lo, uint32_t hi, uint32_t bound, Key key) {
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (key(mid) < bound) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}


// Step of measureBody: the element boundaries of the body's regions (regions + 1 each): struts
// by their first end (i < j), hinges by the lower vertex of their edge.
void regionBoundaries(const Model& model, const BodyInfo& info, uint32_t regions, std::vector<uint32_t>& strutAt,
                      std::vector<uint32_t>& hingeAt) {
  strutAt[0] = info.firstStrut, strutAt[regions] = info.firstStrut + info.strutCount;
  hingeAt[0] = info.firstHinge, hingeAt[regions] = info.firstHinge + info.hingeCount;
  for (uint32_t r = 1; r < regions; ++r) {
    const uint32_t bound = info.firstVertex + r * kRegionVertices;
    strutAt[r] = firstAtLeast(strutAt[r - 1], strutAt[regions], bound,
                              [&](uint32_t s) { return model.struts[s].i; });
    hingeAt[r] = firstAtLeast(hingeAt[r - 1], hingeAt[regions], bound, [&](uint32_t h) {
      return std::min(model.hinges[h].v[0], model.hinges[h].v[1]);
    });
  }
}

// Step of measureBody: the sums over the vertices [begin, end) of one region, in two passes,
// positions then motion: one would hold more running sums than there are registers, and the
// spilled ones wait on memory. `poses`: the moving planes where they are now (or nullptr).
RegionSums sumRegionVertices(const Model& model, const Vec3* x, const Vec3* v, uint32_t begin, uint32_t end,
                             const Pose* poses) {
  RegionSums m;  // a local, so that the running sums stay in registers
  m.lo = m.hi = x[begin];
  bool finite = true;
  for (uint32_t i = begin; i < end; ++i) {
    const double mi = model.mass[i];
    finite = finite && isFinite(x[i]);
    m.mass += mi;
    m.centroid += x[i] * mi;
    m.gravitational -= mi * dot(model.gravity, x[i]);
    m.lo = componentMin(m.lo, x[i]);
    m.hi = componentMax(m.hi, x[i]);
    m.penetration = std::max(m.penetration, model.colliders.planePenetration(x[i], poses));
  }
  for (uint32_t i = begin; i < end; ++i) {
    const double mi = model.mass[i];
    finite = finite && isFinite(v[i]);
    m.momentum += v[i] * mi;
    m.angularMomentum += cross(x[i], v[i]) * mi;
    m.kinetic += 0.5 * mi * lengthSquared(v[i]);
    m.speedSquared += lengthSquared(v[i]);
  }
  m.finite = finite;
  return m;
}

// Step of measureBody: the regions' sums combined in region order (the same numbers on every
// thread count), and the volume from enclosedVolume's chunks' sums.
BodyMeasures combineRegions(const BodyInfo& info, const std::vector<RegionSums>& sums,
                            const std::vector<double>& chunkSum) {
  BodyMeasures m;
  double totalMass = 0.0, speedSquared = 0.0;
  Bounds b = {sums[0].lo, sums[0].hi};
  for (const RegionSums& r : sums) {
    m.finite = m.finite && r.finite;
    totalMass += r.mass;
    m.centroid += r.centroid;
    m.momentum += r.momentum;
    m.angularMomentum += r.angularMomentum;
    m.kinetic += r.kinetic;
    m.gravitational += r.gravitational;
    m.elastic += r.elastic;
    speedSquared += r.speedSquared;
    b.lo = componentMin(b.lo, r.lo);
    b.hi = componentMax(b.hi, r.hi);
    m.penetration = std::max(m.penetration, r.penetration);
    m.maxStrain = std::max(m.maxStrain, r.maxStrain);
  }
  m.centroid = m.centroid / totalMass;
  m.rmsSpeed = std::sqrt(speedSquared / info.vertexCount);
  m.size = length(b.size());
  double six = 0.0;
  for (double c : chunkSum) six += c;
  m.volume = info.open ? 0.0 : six / 6.0;  // an open surface encloses none
  m.elastic += gasEnergy(info, m.volume);
  return m;
}

}  // namespace

BodyMeasures measureBody(const World& world, uint32_t body) {
  return measureBody(world, body, world.positions().data(), world.velocities().data());
}

BodyMeasures measureBody(const World& world, uint32_t body, const Vec3* x, const Vec3* v) {
  const Model& model = world.model();
  const BodyInfo& info = model.bodies[body];
  const uint32_t regions = std::max(1u, (info.vertexCount + kRegionVertices - 1) / kRegionVertices);
  std::vector<uint32_t> strutAt(regions + 1), hingeAt(regions + 1);
  regionBoundaries(model, info, regions, strutAt, hingeAt);
  // The volume in enclosedVolume's chunks, so that it is that function's number exactly; the
  // regions take the chunks in proportion.
  const uint32_t chunks = volumeChunkCount(info);
  std::vector<double> chunkSum(chunks);
  std::vector<RegionSums> sums(regions);
  // The moving planes where they are now.
  std::vector<Pose> planePoses;
  if (model.colliders.moving()) {
    for (const PlaneCollider& pl : model.colliders.planes) planePoses.push_back(pl.motion.pose(world.time()));
  }
  const Pose* poses = planePoses.empty() ? nullptr : planePoses.data();
  world.parallelFor(regions, [&](std::size_t first, std::size_t last) {
    for (std::size_t r = first; r < last; ++r) {
      const uint32_t begin = info.firstVertex + static_cast<uint32_t>(r) * kRegionVertices;
      const uint32_t end = std::min(begin + kRegionVertices, info.firstVertex + info.vertexCount);
      RegionSums m = sumRegionVertices(model, x, v, begin, end, poses);
      const StrutMeasures struts = measureStruts(model.struts.data(), strutAt[r], strutAt[r + 1], x);
      m.elastic = struts.energy + hingeEnergy(model.hinges.data(), hingeAt[r], hingeAt[r + 1], x);
      m.maxStrain = struts.maxStrain;
      for (std::size_t c = r * chunks / regions; c < (r + 1) * chunks / regions; ++c) {
        chunkSum[c] = chunkSixVolume(model, body, static_cast<uint32_t>(c), x);
      }
      sums[r] = m;
    }
  });
  return combineRegions(info, sums, chunkSum);
}

namespace {

// A driver this many times faster than the body's waves, or gravity that would sag it by this
// share of its size, is more than the body can follow at any step (sceneCause). Far from what
// the scenes do: the fastest driver of scenes/ is cape.toml's pins, at 0.1 of its cloth's speed
// (press.toml's plate 0.014, shaker.toml's 0.017); the largest sag is cube.toml's, 1.6% of its
// size.
// The estimates count struts only: a gas holds a body its struts alone would not
// (tests/data/app/gas.toml's balloon, whose struts would sag it by 1.2 times its size).
constexpr double kFasterThanTheBody = 10.0;
constexpr double kSagOfSize = 10.0;

std::string number(double x, bool allDigits = false) {
  char buf[32];
  std::snprintf(buf, sizeof buf, allDigits ? "%.17g" : "%.4g", x);
  return buf;
}

// One thing that drives a body: what the message says, and how far past what the body answers.
struct Drive {
  double ratio = 0.0;
  std::string text;
};

// The top speed at which `motion` moves the point at `at` over [t0, t1], and how it does.
struct MotionSpeed {
  double speed = 0.0;  // [m/s]
  std::string how;
};
MotionSpeed topSpeed(const Movement& motion, double t0, double t1, const Vec3& at) {
  MotionSpeed top;
  const auto consider = [&](double speed, std::string how) {
    if (!(speed <= top.speed)) top = {speed, std::move(how)};
  };
  for (std::size_t k = 1; k < motion.keys.size(); ++k) {
    const Movement::Key &a = motion.keys[k - 1], &b = motion.keys[k];
    if (b.time < t0 || a.time > t1) continue;
    const double distance = length(b.offset - a.offset), span = b.time - a.time;
    // A cubic segment's speed peaks at about 1.5 times its chord's (zero tangents at its ends).
    // Times so close that four digits do not tell them apart get all of theirs.
    const bool close = number(a.time) == number(b.time);
    consider(distance / span * (motion.cubic ? 1.5 : 1.0),
             "its keyframes at t = " + number(a.time, close) + " s and " + number(b.time, close) + " s move it " +
                 number(distance) + " m in " + number(span) + " s");
  }
  if (motion.frequency > 0.0) {
    consider(2.0 * kPi * motion.frequency * length(motion.amplitude),
             "it oscillates by " + number(length(motion.amplitude)) + " m at " + number(motion.frequency) + " Hz");
  }
  if (motion.spin != 0.0) {
    const Vec3 r = at - motion.centre;
    const double radius = length(r - motion.axis * dot(r, motion.axis));
    consider(std::fabs(motion.spin) * radius, "it spins at " + number(std::fabs(motion.spin) * 180.0 / kPi) +
                                                  " deg/s, " + number(radius) + " m from its axis");
  }
  return top;
}

// Whether a triangle collider's rest bounds, carried by its motion over [t0, t1] (at its ends and
// its keys between), come within `margin` of `body`. A spinning one always may.
bool sweepsNear(const TriangleCollider& c, double t0, double t1, const Bounds& body, double margin) {
  if (c.motion.spin != 0.0 || c.nodes.empty() || !isFinite(body.lo) || !isFinite(body.hi)) return true;
  std::vector<double> times{t0, t1};
  for (const Movement::Key& k : c.motion.keys) {
    if (k.time > t0 && k.time < t1) times.push_back(k.time);
  }
  const Vec3 swing = c.motion.amplitude;  // an oscillation reaches this far either way
  Bounds swept{c.nodes[0].lo + c.motion.translation(t0) - swing, c.nodes[0].hi + c.motion.translation(t0) + swing};
  for (double t : times) {
    swept.lo = componentMin(swept.lo, c.nodes[0].lo + c.motion.translation(t) - swing);
    swept.hi = componentMax(swept.hi, c.nodes[0].hi + c.motion.translation(t) + swing);
  }
  for (int a = 0; a < 3; ++a) {
    if (swept.lo[a] > body.hi[a] + margin || swept.hi[a] < body.lo[a] - margin) return false;
  }
  return true;
}

// Whether a moving plane came within `margin` of the body's bounds over [t0, t1]: its placement
// at rest moved by its translation at t0, t1 and the keyframes between, widened by its
// oscillation's reach (a plane far from the body drives nothing there; its spin is left out).
bool planeNear(const PlaneCollider& plane, double t0, double t1, const Bounds& body, double margin) {
  const Vec3 centre = (body.lo + body.hi) * 0.5;
  const Vec3 half = (body.hi - body.lo) * 0.5;
  const Vec3 n = plane.normal;
  const double reach = std::abs(n.x) * half.x + std::abs(n.y) * half.y + std::abs(n.z) * half.z + margin +
                       length(plane.motion.amplitude);
  std::vector<double> times = {t0, t1};
  for (const Movement::Key& k : plane.motion.keys) {
    if (k.time > t0 && k.time < t1) times.push_back(k.time);
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;  // signed distances of the centre
  for (double t : times) {
    const double d = dot(centre - (plane.point + plane.motion.translation(t)), n);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return lo <= reach && hi >= -reach;
}

// Step of sceneCause: the moving colliders and the body's pins, each as fast as it goes over
// [since, now] against the body's speed.
void movingDrives(const World& world, uint32_t body, double since, const BodyResponse& response,
                  std::vector<Drive>& drives) {
  const Model& model = world.model();
  const BodyInfo& info = model.bodies[body];
  const std::vector<Vec3>& x = world.positions();
  const std::vector<Vec3> own(x.begin() + info.firstVertex, x.begin() + info.firstVertex + info.vertexCount);
  const Bounds bounds = boundsOf(own);
  const Vec3 centre = (bounds.lo + bounds.hi) * 0.5;
  const double now = world.time();
  const auto consider = [&](const Movement& motion, const std::string& who) {
    const MotionSpeed top = topSpeed(motion, since, now, centre);
    const double ratio = top.speed / response.speed();
    if (ratio > kFasterThanTheBody) {
      drives.push_back({ratio, who + " moving at " + number(top.speed) + " m/s (" + top.how + "), more than the " +
                                   number(response.speed()) + " m/s at which the body can give way"});
    }
  };
  for (std::size_t p = 0; p < model.colliders.planes.size(); ++p) {
    const PlaneCollider& plane = model.colliders.planes[p];
    if (plane.motion.moves() && planeNear(plane, since, now, bounds, info.restSize)) {
      consider(plane.motion, "[[plane]] #" + std::to_string(p + 1));
    }
  }
  for (const TriangleCollider& c : model.colliders.meshes) {
    if (c.motion.moves() && sweepsNear(c, since, now, bounds, info.restSize)) consider(c.motion, "collider '" + c.name + "'");
  }
  for (const Model::PinTrack& track : model.pinTracks) {
    if (track.body == body && track.motion.moves()) consider(track.motion, "its pins (pin_motion)");
  }
}

}  // namespace

double BodyResponse::sag(double g, double restSize) const {
  const double n = restSize / length;
  return g * n * n / (2.0 * omega * omega);
}

BodyResponse bodyResponse(const Model& model, uint32_t body) {
  const BodyInfo& info = model.bodies[body];
  BodyResponse r;
  if (info.strutCount == 0 || info.vertexCount == 0) return r;
  double stiffness = 0.0, length = 0.0;
  for (uint32_t s = info.firstStrut; s < info.firstStrut + info.strutCount; ++s) {
    stiffness += model.struts[s].stiffness;
    length += model.struts[s].restLength;
  }
  const double vertexMass = info.mass / info.vertexCount;
  r.omega = std::sqrt(stiffness / info.strutCount / vertexMass);
  r.length = length / info.strutCount;
  return r;
}

std::string sceneCause(const World& world, uint32_t body, double since) {
  const Model& model = world.model();

  const BodyInfo& info = model.bodies[body];
  const BodyResponse response = bodyResponse(model, body);
  if (!(response.omega > 0.0) || !(response.length > 0.0)) return "";
  std::vector<Drive> drives;
  const double g = length(model.gravity);
  const double sag = response.sag(g, info.restSize);
  if (sag > kSagOfSize * info.restSize) {
    drives.push_back({sag / info.restSize, "gravity " + number(g) + " m/s^2 (it would sag the body by " + number(sag) +
                                               " m under its own weight, " + number(sag / info.restSize) +
                                               " times its size)"});
  }
  movingDrives(world, body, since, response, drives);
  const auto most = std::max_element(drives.begin(), drives.end(),
                                     [](const Drive& a, const Drive& b) { return a.ratio < b.ratio; });
  return most == drives.end() ? "" : most->text;
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

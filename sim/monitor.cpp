#include "sim/monitor.h"

#include "sim/forces.h"
#include "sim/interrupt.h"
#include "sim/intersections.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

namespace springy {
namespace {

// The lowest point any collider offers along gravity (where a falling body could end up), if any.
std::optional<double> lowestSupport(const Model& model, const Vec3& up) {
  std::optional<double> lowest;
  auto consider = [&](double h) { lowest = lowest ? std::min(*lowest, h) : h; };
  for (const PlaneCollider& p : model.colliders.planes) {
    if (dot(p.normal, up) > 0.5) consider(dot(p.point, up));
  }
  for (const TriangleCollider& t : model.colliders.meshes) {
    for (const Vec3& p : t.mesh.positions) consider(dot(p, up));
  }
  return lowest;
}

Vec3 upOf(const Model& model) {
  const double g = length(model.gravity);
  return g > 0.0 ? model.gravity / -g : Vec3{0, 1, 0};
}

// What a body has left to spend in the state m: kinetic + elastic + its centroid's fall to
// `support` along `up` (at least leastFall) under gravity g.
double energyLeft(const BodyInfo& info, const BodyMeasures& m, const Vec3& up, double g, double support,
                  double leastFall) {
  return m.kinetic + m.elastic + info.mass * g * std::max(leastFall, dot(m.centroid, up) - support);
}

// What a rise above the lowest total is measured against: what was left to spend at the lowest
// (a body at rest on the ground: its fall to flat, m g times its centroid's height), never more
// than the start's scale, and never below a millionth of it (round-off in the gravitational
// energy, counted from the origin, and a body at rest in zero gravity with nothing left).
double lowestAllowance(double scale, double spendableAtLowest) {
  return std::clamp(spendableAtLowest, 1e-6 * scale, scale);
}

std::string describe(const World& world, uint32_t body, const std::string& what, const std::string& advice) {
  std::ostringstream s;
  s << "body '" << world.model().bodies[body].name << "' at step " << world.stepCount() << " (t = " << world.time()
    << " s): " << what << ". " << advice;
  return s.str();
}

// A failure of `body` (not a criterion): what went wrong and what to try, unless the scene drove
// it there since `since` (sceneCause): then that, and that no step fixes it.
Failure failed(const World& world, uint32_t body, const std::string& what, const std::string& advice, double since) {
  const std::string cause = sceneCause(world, body, since);
  if (cause.empty()) return Failure{body, world.stepCount(), world.time(), describe(world, body, what, advice)};
  Failure failure{body, world.stepCount(), world.time(),
                  describe(world, body, what,
                           "A smaller step does not fix it: " + cause +
                               ". The scene asks more of the body than it can follow: lower what drives it (gravity, "
                               "a motion's speed: spread its keyframes), or stiffen the body (shorter strut_period "
                               "or stretch_period).")};
  failure.cause = cause;
  return failure;
}

// What to try after an instability; a body with gas also has a volume_period to lengthen.
std::string stepAdvice(const BodyInfo& body) {
  const bool own = body.membraneModulus > 0.0;  // the body material
  return std::string(
             "Try a smaller dt or more substeps (--substeps N, or --substeps auto: a count tried over the "
             "whole run), an adaptive step (--tolerance 1e-4: it shortens its steps as the body stiffens), a "
             "more stable integrator (rk4, verlet), or softer springs (longer ") +
         (own ? "stretch_period / bend_period" : "strut_period / hinge_period") +
         (body.gasPressure > 0.0 ? " / volume_period" : "") + "); `springy suggest` estimates a stable dt.";
}


// Step of Monitor::check: a contact search that overflowed did not act, and the bodies' state
// explains why: reported first.
std::optional<Failure> contactOverflowFailure(const World& world, double since) {
  const Model& model = world.model();
  const BodyContacts* contacts = world.bodyContacts();
  if (!contacts || contacts->sinceStart().overflows == 0) return std::nullopt;
  const auto [a, b] = contacts->overflowPair();
  std::ostringstream s;
  s << "the contact search between it and " << (a == b ? "itself" : "body '" + model.bodies[b].name + "'")
    << " found more than " << kMaxCandidatesPerPrimitive
    << " candidate pairs per primitive (bodies that have blown up, or start inside each other)";
  return failed(world, a, s.str(), stepAdvice(model.bodies[a]), since);
}

// What keeps a body's shape, for a body that lost it.
std::string keepShapeAdvice(const BodyInfo& info) {
  return info.membraneModulus > 0.0
             ? "The body is too soft to keep its shape: try a shorter bend_period or stretch_period "
               "(`springy suggest --keep-volume` finds them), or a gas (volume_period)."
             : "The body is too soft to keep its shape: try a shorter hinge_period (stiffer hinges; "
               "their bending stiffness falls with the cube of the mesh spacing) or a shorter "
               "strut_period, or the body material (scenes/README.md), which means the same at "
               "every resolution.";
}

// The failure of a body whose volume fell to `ratio` of rest, below the required `minVolume`
// (a limit the run was given, not an instability), with what would keep its shape.
Failure volumeFailure(const World& world, uint32_t b, double ratio, double minVolume) {
  const BodyInfo& info = world.model().bodies[b];
  std::ostringstream s;
  s << "its volume fell to " << 100.0 * ratio << "% of rest, below the required " << 100.0 * minVolume << "%";
  Failure failure{b, world.stepCount(), world.time(), describe(world, b, s.str(), keepShapeAdvice(info))};
  failure.criterion = true;
  return failure;
}

// Whether a closed body's volume says it collapsed (kCollapsedVolume): at or below that share of
// its rest volume or of `before` (its volume at the last frame), or not a number.
bool collapsed(const BodyInfo& info, double volume, double before) {
  return info.restVolume > 0.0 && !(volume > kCollapsedVolume * std::max(info.restVolume, before));
}

// The failure of a closed body whose volume collapsed (collapsed()): NaN, blown up through
// itself, inside out, crushed flat or folded.
Failure collapseFailure(const World& world, uint32_t b, double volume, double before, double since) {
  const BodyInfo& info = world.model().bodies[b];
  if (!std::isfinite(volume)) return failed(world, b, "a position or velocity is NaN or infinite", stepAdvice(info), since);
  const double ratio = volume / info.restVolume;
  std::ostringstream s;
  if (ratio < -0.5) {
    // Through itself to more than half its size inside out: no crush does that, an instability
    // does (an explicit step far past its limit, a gas whose period the step does not resolve).
    s << "it blew up: it turned inside out to " << 100.0 * ratio << "% of its rest volume";
    return failed(world, b, s.str(), stepAdvice(info), since);
  }
  if (volume < 0.0) {
    s << "it turned inside out: its volume is " << 100.0 * ratio << "% of rest";
  } else if (ratio < 1e-9) {
    s << "it was crushed flat: its volume is " << 100.0 * ratio << "% of rest";
  } else {
    s << "it collapsed to " << 100.0 * ratio << "% of its rest volume";
  }
  s << " (" << 100.0 * before / info.restVolume << "% at the last frame; a closed body below "
    << 100.0 * kCollapsedVolume << "% has lost its shape)";
  Failure failure = failed(world, b, s.str(), keepShapeAdvice(info), since);
  if (volume <= 0.0 && !info.selfContact && failure.cause.empty()) {
    // Inside out: a crush folded it through itself, which its own contact would stop.
    failure.message += " If it folded through itself, with self_contact = true its own faces stop it "
                       "(docs/model.md section 19; it costs run time).";
  }
  return failure;
}

// Step of Monitor::check: bodies crossing each other or themselves: whatever the contact stage
// did, never a silent pass-through (sim/intersections.h).
std::optional<Failure> bodyCrossingFailure(const World& world, double since) {
  const Model& model = world.model();
  if (world.bodyContacts() == nullptr) return std::nullopt;
  const std::vector<Intersection> crossing = findIntersections(model, world.positions(), 1);
  if (crossing.empty()) return std::nullopt;
  const Intersection& c = crossing[0];
  const BodyInfo &a = model.bodies[c.bodyA], &b = model.bodies[c.bodyB];
  std::ostringstream s;
  if (c.bodyA == c.bodyB) {
    s << "it passes through itself: its faces " << c.faceA - a.firstFace << " and " << c.faceB - a.firstFace;
  } else {
    s << "it passes through body '" << b.name << "': its face " << c.faceA - a.firstFace << " and face "
      << c.faceB - b.firstFace << " of '" << b.name << "'";
  }
  s << " cross at (" << c.point.x << ", " << c.point.y << ", " << c.point.z << ")";
  return failed(world, c.bodyA, s.str(),
                "The contact let it through: try a smaller dt or more substeps (--substeps), or a larger "
                "contact_thickness; if dt is sane, please report the scene.",
                since);
}

// Step of Monitor::check: bodies through a collider mesh, still or moving: its contact stops
// vertices, and an edge that passes through a triangle (or a triangle's edge through a face) is
// caught here.
std::optional<Failure> colliderCrossingFailure(const World& world, double since) {
  const Model& model = world.model();
  if (model.colliders.meshes.empty()) return std::nullopt;
  const std::vector<ColliderCrossing> crossing = findColliderCrossings(model, world.positions(), world.time(), 1);
  if (crossing.empty()) return std::nullopt;
  const ColliderCrossing& c = crossing[0];
  const BodyInfo& a = model.bodies[c.body];
  std::ostringstream s;
  s << "it passes through collider '" << model.colliders.meshes[c.collider].name << "': its face "
    << c.face - a.firstFace << " and the collider's triangle " << c.triangle << " cross at (" << c.point.x << ", "
    << c.point.y << ", " << c.point.z << ")";
  return failed(world, c.body, s.str(),
                "The contact let it through: try a smaller dt or more substeps (--substeps), a larger "
                "contact_thickness, or a finer body mesh (a coarse one drapes over a collider's edges "
                "and corners with its faces, which only its vertices are kept off)",
                since);
}

}  // namespace

double landingStep(const World& world, uint32_t body, double tolerance) {
  const Model& model = world.model();
  const double g = length(model.gravity);
  const Vec3 up = upOf(model);
  const std::optional<double> support = lowestSupport(model, up);
  const BodyInfo& info = model.bodies[body];
  if (!(g > 0.0) || !support || !(info.mass > 0.0)) return std::numeric_limits<double>::infinity();
  double lowest = std::numeric_limits<double>::infinity();
  const std::vector<Vec3>& x = world.positions();
  for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount; ++i)
    lowest = std::min(lowest, dot(x[i], up));
  const BodyMeasures m = measureBody(world, body);
  const double speed = std::sqrt(2.0 * m.kinetic / info.mass + 2.0 * g * std::max(0.0, lowest - *support));
  const double left = energyLeft(info, m, up, g, *support, 0.0);
  if (!(speed > 0.0)) return std::numeric_limits<double>::infinity();
  // The bounce takes (1 - e^2) m v^2 / 2 from every vertex that lands, in the same step: the
  // gain m g v h shows as a rise only past h = (1 - e^2) v / 2g (e: the most elastic collider's).
  double restitution = 0.0;
  for (const PlaneCollider& p : model.colliders.planes) restitution = std::max(restitution, p.material.restitution);
  for (const TriangleCollider& t : model.colliders.meshes)
    restitution = std::max(restitution, t.material.restitution);
  const double bounce = (1.0 - restitution * restitution) * speed / (2.0 * g);
  return tolerance * left / (info.mass * g * speed) + bounce;
}

Monitor::Monitor(const World& world, MonitorLimits limits) : limits_(limits) {
  const Model& model = world.model();
  // With wind, colliders that move or pins that follow a track, energy is injected from outside:
  // the energy check would be meaningless.
  bool drivenPins = false;
  for (const Model::PinTrack& track : model.pinTracks) drivenPins = drivenPins || track.motion.moves();
  // Soft attachments store energy the measures do not count (and, to a moving collider, take
  // it in).
  checkEnergy_ = !model.wind.has_value() && !model.colliders.moving() && !drivenPins && model.attachments.empty();
  lowestBased_ = limits_.energyFromLowest && !energySwings(world.integrator());
  g_ = length(model.gravity);
  up_ = upOf(model);
  checkedAt_[0] = checkedAt_[1] = world.time();
  const std::optional<double> support = lowestSupport(model, up_);
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    BodyRecord r;
    r.start = r.last = measureBody(world, b);
    const BodyInfo& info = model.bodies[b];
    // Without colliders, its own rest size below it.
    support_.push_back(support ? *support : dot(r.start.centroid, up_) - info.restSize);
    // At least the energy of lifting the body by its own size: the scale is not zero for a
    // body that starts at rest on the ground or in zero gravity.
    r.energyScale = std::max(spendable(info, b, r.start, info.restSize), 1e-12);
    r.lowestTotal = r.start.total();
    r.lowestTotalTime = world.time();
    r.lowestSpendable = r.energyScale;
    records_.push_back(r);
    frameVolume_.push_back(r.start.volume);
  }
  if (world.bodyContacts() != nullptr) {
    for (uint32_t b = 0; b < model.bodies.size(); ++b) {
      if (!model.bodies[b].contact) continue;
      touching_.push_back(b);
      touchingScale_ += records_[b].energyScale;
      touchingLowest_ += records_[b].start.total();
    }
    touchingSpendable_ = touchingScale_;
    if (touching_.size() < 2) touching_.clear();
    touchingLowestTime_ = world.time();
  }
}

double Monitor::spendable(const BodyInfo& info, uint32_t body, const BodyMeasures& m, double leastFall) const {
  return energyLeft(info, m, up_, g_, support_[body], leastFall);
}

void Monitor::readAtOneInstant(const World& world, uint32_t body, BodyMeasures& m) {
  if (synchronized_ == Synchronized::NotYet)
    synchronized_ = world.synchronizedState(xSync_, vSync_) ? Synchronized::Yes : Synchronized::No;
  if (synchronized_ == Synchronized::Yes) {
    const BodyMeasures e = measureBody(world, body, xSync_.data(), vSync_.data());
    m.kinetic = e.kinetic, m.gravitational = e.gravitational, m.elastic = e.elastic;
  }
}

std::optional<Failure> Monitor::checkBody(const World& world, uint32_t b) {
  BodyRecord& r = records_[b];
  const BodyInfo& info = world.model().bodies[b];
  BodyMeasures m = measureBody(world, b);
  r.last = m;
  auto fail = [&](const std::string& what, const std::string& advice) {
    return failed(world, b, what, advice, checkedAt_[0]);
  };
  if (!m.finite) return fail("a position or velocity is NaN or infinite", stepAdvice(info));
  if (m.size > limits_.sizeFactor * info.restSize) {
    std::ostringstream s;
    s << "it blew up to " << m.size / info.restSize << " times its rest size";
    return fail(s.str(), stepAdvice(info));
  }
  // Nothing injects energy, so the total may only fall: a rise above the lowest total so far
  // (not only above the start: a body that has lost most of its energy and gains it back at
  // rest is as wrong) is an instability.
  const bool touching = std::binary_search(touching_.begin(), touching_.end(), b);
  // Counted from the lowest, the rise is measured against what the body had left to spend
  // then, not what it had at the start: an instability that saturates (its pumping balanced by
  // damping and drag) is no longer hidden under 2 % of the start's scale. Not for the
  // symplectic methods, whose energy at a stable step swings by a multiple of a mode's
  // (energySwings): a swing of what is left would read as a rise. From the start, against the
  // start's.
  const double reference = limits_.energyFromLowest ? r.lowestTotal : r.start.total();
  const double allowed = limits_.energyTolerance * (lowestBased_ ? lowestAllowance(r.energyScale, r.lowestSpendable)
                                                                  : r.energyScale);
  const auto rose = [&] { return m.total() - reference > allowed; };
  if (checkEnergy_ && !touching && rose()) readAtOneInstant(world, b, m);
  if (checkEnergy_ && !touching && rose()) {
    std::ostringstream s;
    s << "its total energy rose from " << reference << " J";
    if (limits_.energyFromLowest) s << " (its lowest, at t = " << r.lowestTotalTime << " s)";
    s << " to " << m.total() << " J, more than " << allowed
      << " J, although nothing injects energy (the integration is unstable or too coarse)";
    return fail(s.str(), stepAdvice(info));
  }
  r.last = m;
  if (m.total() < r.lowestTotal) {
    r.lowestTotal = m.total(), r.lowestTotalTime = world.time();
    r.lowestSpendable = spendable(info, b, m, 0.0);
  }
  if (m.penetration > limits_.penetration * info.restSize) {
    std::ostringstream s;
    s << "a vertex is " << m.penetration << " m behind a plane";
    return fail(s.str(), "This is a bug in contact handling if dt is sane; please report the scene.");
  }
  r.maxStrain = std::max(r.maxStrain, m.maxStrain);
  r.maxPenetration = std::max(r.maxPenetration, m.penetration);
  if (collapsed(info, m.volume, frameVolume_[b])) return collapseFailure(world, b, m.volume, frameVolume_[b], checkedAt_[0]);
  frameVolume_[b] = m.volume;
  if (info.restVolume > 0.0) {
    const double ratio = m.volume / info.restVolume;
    r.minVolumeRatio = std::min(r.minVolumeRatio, ratio);
    r.maxVolumeRatio = std::max(r.maxVolumeRatio, ratio);
    if (ratio < limits_.minVolume) return volumeFailure(world, b, ratio, limits_.minVolume);
  }
  return std::nullopt;
}

std::optional<Failure> Monitor::checkTouchingEnergy(const World& world) {
  const Model& model = world.model();
  // The bodies in contact together: the one whose own energy rose most above its lowest is
  // named (energy passes from body to body, but the sum may only fall).
  double total = 0.0, start = 0.0, rise = -INFINITY;
  uint32_t named = touching_[0];
  for (uint32_t b : touching_) {
    total += records_[b].last.total();
    start += records_[b].start.total();
    if (records_[b].last.total() - records_[b].lowestTotal > rise) {
      rise = records_[b].last.total() - records_[b].lowestTotal;
      named = b;
    }
  }
  const double reference = limits_.energyFromLowest ? touchingLowest_ : start;
  const double allowed = limits_.energyTolerance *
                         (lowestBased_ ? lowestAllowance(touchingScale_, touchingSpendable_) : touchingScale_);
  if (total - reference > allowed) {
    // Read at one instant (symplectic Euler), the rise may go.
    total = 0.0;
    for (uint32_t b : touching_) {
      readAtOneInstant(world, b, records_[b].last);
      total += records_[b].last.total();
    }
  }
  if (total - reference > allowed) {
    std::ostringstream s;
    s << "the total energy of the bodies in contact (";
    for (std::size_t k = 0; k < touching_.size(); ++k)
      s << (k ? ", " : "") << "'" << model.bodies[touching_[k]].name << "'";
    s << ") rose from " << reference << " J";
    if (limits_.energyFromLowest) s << " (its lowest, at t = " << touchingLowestTime_ << " s)";
    s << " to " << total << " J, more than " << allowed
      << " J, although nothing injects energy (the integration or the contact is unstable or too coarse)";
    return failed(world, named, s.str(), stepAdvice(model.bodies[named]), checkedAt_[0]);
  }
  if (total < touchingLowest_) {
    touchingLowest_ = total, touchingLowestTime_ = world.time();
    touchingSpendable_ = 0.0;
    for (uint32_t b : touching_) touchingSpendable_ += spendable(model.bodies[b], b, records_[b].last, 0.0);
  }
  return std::nullopt;
}

std::optional<Failure> Monitor::check(const World& world) {
  if (watched_) return watched_;
  std::optional<Failure> failure = checkAll(world);
  checkedAt_[0] = checkedAt_[1], checkedAt_[1] = world.time();
  return failure;
}

std::optional<Failure> Monitor::watchStep(const World& world) {
  if (watched_) return watched_;
  const Model& model = world.model();
  const Vec3* x = world.positions().data();
  for (uint32_t b = 0; b < model.bodies.size() && !watched_; ++b) {
    const BodyInfo& info = model.bodies[b];
    if (info.restVolume > 0.0) {
      // Enclosed volume's own sum, as measureBody's: the same number a frame's check sees.
      const double volume = enclosedVolume(model, b, x);
      if (collapsed(info, volume, frameVolume_[b]))
        watched_ = collapseFailure(world, b, volume, frameVolume_[b], checkedAt_[0]);
      continue;
    }
    for (uint32_t v = info.firstVertex; v < info.firstVertex + info.vertexCount; ++v) {
      if (isFinite(x[v])) continue;
      watched_ = failed(world, b, "a position or velocity is NaN or infinite", stepAdvice(info), checkedAt_[0]);
      break;
    }
  }
  return watched_;
}

std::optional<Failure> Monitor::checkAll(const World& world) {
  const double since = checkedAt_[0];
  if (std::optional<Failure> failure = contactOverflowFailure(world, since)) return failure;
  synchronized_ = Synchronized::NotYet;
  for (uint32_t b = 0; b < world.model().bodies.size(); ++b) {
    if (std::optional<Failure> failure = checkBody(world, b)) return failure;
  }
  if (checkEnergy_ && !touching_.empty()) {
    if (std::optional<Failure> failure = checkTouchingEnergy(world)) return failure;
  }
  if (std::optional<Failure> failure = bodyCrossingFailure(world, since)) return failure;
  return colliderCrossingFailure(world, since);
}

void RestWatch::add(const std::vector<Vec3>& x) {
  if (lo_.empty()) {
    lo_ = x;
    hi_ = x;
    return;
  }
  for (std::size_t i = 0; i < x.size(); ++i) {
    lo_[i] = componentMin(lo_[i], x[i]);
    hi_[i] = componentMax(hi_[i], x[i]);
  }
}

std::pair<double, uint32_t> RestWatch::largestMove(const BodyInfo& info) const {
  double moved = 0.0;
  uint32_t worst = info.firstVertex;
  for (uint32_t i = info.firstVertex; i < info.firstVertex + info.vertexCount && i < lo_.size(); ++i) {
    const double extent = length(hi_[i] - lo_[i]);
    if (extent > moved) moved = extent, worst = i;
  }
  return {moved, worst};
}

bool stepTo(World& world, double time, Monitor* monitor) {
  while (!world.reached(time)) {
    if (interrupted()) return false;
    world.stepToward(time);
    if (!world.stepProblem().empty()) return false;
    if (monitor && monitor->watchStep(world)) return false;
  }
  return true;
}

Failure stepFailure(const World& world, double since) {
  Failure failure{0, world.stepCount(), world.time(), world.stepProblem()};
  for (uint32_t b = 0; b < world.model().bodies.size(); ++b) {
    failure.cause = sceneCause(world, b, since);
    if (failure.cause.empty()) continue;
    failure.body = b;
    failure.message += ". A smaller step does not fix it: body '" + world.model().bodies[b].name + "' is driven by " +
                       failure.cause + ".";
    break;
  }
  return failure;
}

std::optional<Failure> advanceTo(World& world, Monitor& monitor, double time) {
  const double since = monitor.since();
  const bool reached = stepTo(world, time, &monitor);
  if (!reached && world.stepProblem().empty() && !monitor.watched()) return std::nullopt;  // interrupted
  std::optional<Failure> failure = monitor.check(world);
  if (failure || world.stepProblem().empty()) return failure;
  return stepFailure(world, since);
}

}  // namespace springy

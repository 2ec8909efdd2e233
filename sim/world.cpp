#include "sim/world.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>

#include "sim/error.h"
#include "sim/implicit.h"
#include "sim/vbd.h"
#include "sim/stability.h"

namespace springy {
namespace {

// The largest of fn(i) over [begin, end) (0 for none); a NaN wins (it must stop the step).
template <class F>
double largestOver(std::size_t begin, std::size_t end, F&& fn) {
  double m = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    const double e = fn(i);
    if (!(e <= m)) m = std::isnan(m) ? m : e;
  }
  return m;
}

// Folds a share's largest value into `out` (one compare-and-swap per share; a maximum does not
// depend on the order shares finish in, so neither does the result).
void foldLargest(std::atomic<double>& out, double value) {
  double seen = out.load(std::memory_order_relaxed);
  while ((value > seen || (std::isnan(value) && !std::isnan(seen))) &&
         !out.compare_exchange_weak(seen, value, std::memory_order_relaxed)) {
  }
}

}  // namespace

namespace {

// The model as a World keeps it, immutable from here on: the colliders' trees built (setup builds
// them; a model made by hand, as in the tests, gets them here).
std::unique_ptr<const Model> finished(Model model) {
  for (TriangleCollider& tc : model.colliders.meshes) {
    if (tc.nodes.empty()) tc.buildBvh();
  }
  return std::make_unique<const Model>(std::move(model));
}

}  // namespace

World::World(Model model, Integrator integrator, double dt)
    : model_(finished(std::move(model))), integrator_(integrator), dt_(dt), drivers_(*model_) {
  assert(dt > 0.0);
  dampingLayers_ = model_->colliders.dampingLayers();
  if (!integratorRefuses(integrator, drivers_.movingColliders(), false).empty()) {
    throw Error("colliders that move are not supported with " + std::string(integratorName(integrator)) +
                " (its solve holds the colliders still); use rk4, verlet or an adaptive step (--tolerance)");
  }
  if (!integratorRefuses(integrator, false, !model_->attachments.empty()).empty()) {
    throw Error("soft attachments ([[attach]] with a period) are not supported with " +
                std::string(integratorName(integrator)) +
                " (its solve does not have them); use rk4, verlet or an adaptive step (--tolerance)");
  }
  forces_ = std::make_unique<Forces>(*model_);
  if (BodyContacts::needed(*model_)) contacts_ = std::make_unique<BodyContacts>(*model_);

  const std::size_t n = model_->vertexCount();
  state_.x = model_->restPosition;
  state_.v = model_->initialVelocity;
  state_.invMass = model_->invMass;
  state_.released.assign(drivers_.pinTracks(), 0);
  forces_->setInverseMasses(state_.invMass.data());
  if (contacts_) contacts_->setInverseMasses(state_.invMass.data());
  followPins();
  for (auto* buffer : {&xOld_, &a_}) buffer->assign(n, Vec3{});
  if (!model_->colliders.empty()) sinceContact_.assign(n, 0xFFFF);
  restingSteps_ = static_cast<int>(std::ceil(model_->colliders.restingWindow / dt_));
  if (integrator_ == Integrator::RK4) {
    for (auto* buffer : {&k1v_, &k2x_, &k2v_, &k3x_, &k3v_, &k4v_, &xs_, &vs_}) buffer->assign(n, Vec3{});
  }
  if (integrator_ == Integrator::VelocityVerlet || integrator_ == Integrator::Leapfrog) vs_.assign(n, Vec3{});
  if (integrator_ == Integrator::VelocityVerlet) aNext_.assign(n, Vec3{});
  if (integrator_ == Integrator::BackwardEuler) implicit_ = std::make_unique<ImplicitSolver>(*model_);
  if (integrator_ == Integrator::Vbd) vbd_ = std::make_unique<VbdSolver>(*model_);
  if (integrator_ == Integrator::BogackiShampine) {
    for (auto* buffer : {&k2x_, &k3x_, &k3v_, &xs_}) buffer->assign(n, Vec3{});
  }
  if (adaptive()) {
    for (auto* buffer : {&k1v_, &k2v_, &vs_, &xn_, &vn_}) buffer->assign(n, Vec3{});
    if (contacts_) vBefore_.assign(n, Vec3{});
    if (!model_->colliders.empty()) {
      lastContactTime_.assign(n, -std::numeric_limits<double>::infinity());
      candidateHit_.assign(n, 0);
    }
    adaptive_.setFirstStep(dt_);
    setTolerance(adaptive_.tolerance());
    updateStableStep();
  }
}


void World::setTolerance(double tolerance) { adaptive_.setTolerance(*model_, tolerance); }


bool World::restingAt(std::size_t i) const {
  if (adaptive()) return state_.time - lastContactTime_[i] <= model_->colliders.restingWindow;
  return sinceContact_[i] <= restingSteps_;
}

template <class F>
void World::forVertices(F&& fn) const {
  parallelFor(model_->vertexCount(), fn);
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

void World::setState(std::vector<Vec3> x, std::vector<Vec3> v, double time) {
  assert(x.size() == model_->vertexCount() && v.size() == model_->vertexCount());
  // Copied into the state's own buffers: their addresses never change (the Python module's views).
  std::copy(x.begin(), x.end(), state_.x.begin());
  std::copy(v.begin(), v.end(), state_.v.begin());
  state_.time = time;
  cachedAccelerationValid_ = false;
  staggered_ = false;
  std::fill(sinceContact_.begin(), sinceContact_.end(), 0xFFFF);
  std::fill(lastContactTime_.begin(), lastContactTime_.end(), -std::numeric_limits<double>::infinity());
}

void World::step() {
  // Contacts need the positions at the start of the step (xOld). The integrators that change
  // x only in their last pass save it there (lastPass); the others save it now.
  if (keepsOld() && !savesOldInLastPass()) {
    Vec3 *x = state_.x.data(), *xOld = xOld_.data();
    forVertices([&](std::size_t begin, std::size_t end) { std::copy(x + begin, x + end, xOld + begin); });
  }
  // The moving colliders over the step (the adaptive step sets them for each size it tries).
  if (!adaptive()) drivers_.over(state_.time, state_.time + dt_);
  // Integrate; every integrator's last pass over the vertices resolves their contacts too.
  switch (integrator_) {
    case Integrator::ExplicitEuler: stepExplicitEuler(); break;
    case Integrator::SymplecticEuler: stepSymplecticEuler(); break;
    case Integrator::VelocityVerlet: stepVelocityVerlet(); break;
    case Integrator::Leapfrog: stepLeapfrog(); break;
    case Integrator::RK4: stepRK4(); break;
    case Integrator::BackwardEuler: stepBackwardEuler(); break;
    case Integrator::BogackiShampine: stepBogackiShampine(); break;
    case Integrator::AdaptiveVerlet: stepAdaptiveVerlet(); break;
    case Integrator::Vbd: stepVbd(); break;
  }
  if (!adaptive_.problem().empty()) return;  // the adaptive step found no step it could take
  // Contact between and within bodies, over the whole step's paths.
  if (contacts_) {
    if (adaptive()) std::copy(state_.v.begin(), state_.v.end(), vBefore_.begin());
    if (contacts_->resolve(xOld_, state_.x, state_.v, dt_)) {
      cachedAccelerationValid_ = false;
      // The adaptive step: a velocity change dv applied at the end of the step instead of at
      // the contact (on average half-way) misplaces the vertex by about |dv| h / 2; the next
      // step is kept short enough for that to stay within the tolerance.
      if (adaptive()) {
        const Vec3 *v = state_.v.data(), *vb = vBefore_.data();
        const double* inv = adaptive_.inverseScale().data();
        const double h = dt_;
        std::atomic<double> worst{0.0};
        forVertices([&](std::size_t begin, std::size_t end) {
          foldLargest(worst,
                      largestOver(begin, end, [&](std::size_t i) { return length(v[i] - vb[i]) * 0.5 * h * inv[i]; }));
        });
        const double e = worst.load();
        adaptive_.limitAfterContact(h, e);
      }
    }
  }
  state_.time = adaptive() && adaptive_.landed() ? adaptive_.landAt() : state_.time + dt_;
  ++state_.steps;
  if (drivers_.pinTracks() > 0) followPins();
}

void World::addAttachments(const Vec3* x, const Vec3* v, double t, Vec3* a) const {
  // Serial, in the model's order: the same sums on any thread count.
  const Model& m = *model_;
  for (const Model::Attachment& s : m.attachments) {
    if (t >= s.release) continue;
    Vec3 end, endVelocity;
    if (s.other != Model::Attachment::kNone) {
      end = x[s.other];
      endVelocity = v[s.other];
    } else {
      const Movement& motion = m.colliders.meshes[s.collider].motion;
      end = motion.moves() ? motion.pose(t).apply(s.anchor) : s.anchor;
      endVelocity = motion.moves() ? motion.velocityAt(end, t) : Vec3{};
    }
    const Vec3 d = end - x[s.vertex], u = endVelocity - v[s.vertex];
    Vec3 f;
    const double len = length(d);
    if (s.rest > 0.0 && len > 0.0) {
      const Vec3 dir = d / len;
      f = dir * (s.k * (len - s.rest) + s.d * dot(u, dir));
    } else {
      f = d * s.k + u * s.d;
    }
    a[s.vertex] += f * state_.invMass[s.vertex];
    if (s.other != Model::Attachment::kNone) a[s.other] -= f * state_.invMass[s.other];
  }
}

void World::followPins() {
  if (drivers_.follow(state_)) cachedAccelerationValid_ = false;
}

void World::stepExplicitEuler() {
  const double dt = dt_, t = state_.time;
  Vec3 *x = state_.x.data(), *v = state_.v.data(), *a = a_.data();
  accelerations(x, v, t, a);
  lastPass([&](std::size_t i) {
    x[i] += v[i] * dt;
    v[i] += a[i] * dt;
  });
}

void World::stepSymplecticEuler() {
  const double dt = dt_, t = state_.time;
  Vec3 *x = state_.x.data(), *v = state_.v.data(), *a = a_.data();
  accelerations(x, v, t, a);
  lastPass([&](std::size_t i) {
    v[i] += a[i] * dt;
    x[i] += v[i] * dt;
  });
  staggered_ = true;  // a_ keeps a(x(n)) for synchronizedState
}

bool World::synchronizedState(std::vector<Vec3>& x, std::vector<Vec3>& v) const {
  if (!staggered_ || integrator_ != Integrator::SymplecticEuler) return false;
  const std::size_t n = state_.x.size();
  x.resize(n);
  v.resize(n);
  const bool old = keepsOld();  // xOld is x(n) exactly, also where a contact moved a vertex
  forVertices([&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      x[i] = old ? xOld_[i] : state_.x[i] - state_.v[i] * dt_;
      v[i] = state_.v[i] - a_[i] * (0.5 * dt_);
    }
  });
  return true;
}

void World::stepVelocityVerlet() {
  // a(t) is the a(t + dt) of the previous step unless a contact between bodies changed the state
  // since. The static colliders act on the drifted positions before a(t + dt) is evaluated there,
  // with the velocity predictor as the velocity they change; the change carries over to v(t + dt).
  // Forces are then never evaluated at a vertex behind a collider (resolved after the evaluation, a
  // vertex that hit the ground pulled its neighbours down for half a step), and a(t + dt) stays
  // valid for the next step, which no longer evaluates again after a contact. The errors through
  // contact, mostly smaller and on some scenes larger: docs/model.md §14, docs/accuracy-contact.md.
  const double dt = dt_, t = state_.time;
  Vec3 *x = state_.x.data(), *v = state_.v.data(), *a = a_.data(), *vs = vs_.data(), *aNext = aNext_.data();
  if (!cachedAccelerationValid_) accelerations(x, v, t, a);
  const bool contacts = !model_->colliders.empty();
  forVertices([&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      x[i] += v[i] * dt + a[i] * (0.5 * dt * dt);
      vs[i] = v[i] + a[i] * dt;  // velocity predictor for the velocity-dependent forces
    }
    if (contacts) collide(begin, end, vs);
  });
  accelerations(x, vs, t + dt, aNext);
  cachedAccelerationValid_ = true;
  forVertices([&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 change = vs[i] - (v[i] + a[i] * dt);
      v[i] += (a[i] + aNext[i]) * (0.5 * dt) + change;
      a[i] = aNext[i];
    }
  });
}

void World::stepLeapfrog() {
  // Forces at both ends of the step. The closing kick needs a(t + dt) at the velocity
  // v(t + dt), which it is about to compute; the half-step velocity plus the first half
  // kick once more predicts it to O(dt^2), which keeps the scheme second order when the
  // forces depend on velocity (dampers, drag). With position-only forces it is exact KDK.
  const double dt = dt_, t = state_.time;
  Vec3 *x = state_.x.data(), *v = state_.v.data(), *a = a_.data(), *vs = vs_.data();
  accelerations(x, v, t, a);
  forVertices([&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      v[i] += a[i] * (0.5 * dt);          // kick
      x[i] += v[i] * dt;                  // drift
      vs[i] = v[i] + a[i] * (0.5 * dt);   // predicted v(t + dt)
    }
  });
  accelerations(x, vs, t + dt, a);
  lastPass([&](std::size_t i) { v[i] += a[i] * (0.5 * dt); });  // kick
}

void World::stepRK4() {
  const double dt = dt_, t = state_.time;
  Vec3 *x = state_.x.data(), *v = state_.v.data();
  // k1 = f(y), k2 = f(y + dt/2 k1), k3 = f(y + dt/2 k2), k4 = f(y + dt k3); the position
  // slopes are the stage velocities, the velocity slopes the stage accelerations.
  // k1x is the velocity itself (read, not copied: v changes only in the final update, after
  // its own k1x[i] is read).
  const Vec3* k1x = v;
  Vec3 *k1v = k1v_.data(), *k2x = k2x_.data(), *k2v = k2v_.data();
  Vec3 *k3x = k3x_.data(), *k3v = k3v_.data(), *k4v = k4v_.data(), *xs = xs_.data(), *vs = vs_.data();
  // Stage state y + h k for the next evaluation; the stage's velocity is also its position
  // slope, kept in kx.
  const auto stageState = [&](double h, const Vec3* kx, const Vec3* kv, Vec3* nextKx) {
    forVertices([&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        xs[i] = x[i] + kx[i] * h;
        vs[i] = v[i] + kv[i] * h;
        if (nextKx != nullptr) nextKx[i] = vs[i];
      }
    });
  };
  accelerations(x, v, t, k1v);
  stageState(0.5 * dt, k1x, k1v, k2x);
  accelerations(xs, vs, t + 0.5 * dt, k2v);
  stageState(0.5 * dt, k2x, k2v, k3x);
  accelerations(xs, vs, t + 0.5 * dt, k3v);
  stageState(dt, k3x, k3v, nullptr);
  accelerations(xs, vs, t + dt, k4v);
  const double w = dt / 6.0;
  lastPass([&](std::size_t i) {
    // k4x = vs (the fourth stage's velocity).
    x[i] += (k1x[i] + (k2x[i] + k3x[i]) * 2.0 + vs[i]) * w;
    v[i] += (k1v[i] + (k2v[i] + k3v[i]) * 2.0 + k4v[i]) * w;
  });
}

void World::stepBackwardEuler() {
  implicit_->step(*forces_, state_.x, state_.v, state_.time, dt_);
  if (!model_->colliders.empty()) lastPass([](std::size_t) {});  // the static colliders' pass
}

void World::stepVbd() {
  vbd_->step(*forces_, state_.x, state_.v, state_.time, dt_);
  // Restitution and friction, on the velocities the held vertices arrived with (VbdSolver::arrive).
  if (!model_->colliders.empty()) lastPass([&](std::size_t i) { vbd_->arrive(static_cast<uint32_t>(i), state_.x[i], state_.v[i]); });
}

void World::setIterations(int iterations) {
  if (vbd_) vbd_->setIterations(iterations);
}



void World::stepBogackiShampine() {
  // Bogacki & Shampine, "A 3(2) pair of Runge-Kutta formulas", Appl. Math. Lett. 2 (1989):
  //   k1 = f(y), k2 = f(y + h/2 k1), k3 = f(y + 3h/4 k2),
  //   y1 = y + h (2/9 k1 + 1/3 k2 + 4/9 k3)                      (third order)
  //   y1 - y1^ = h (-5/72 k1 + 1/12 k2 + 1/9 k3 - 1/8 k4),  k4 = f(y1)
  // The estimate is taken in positions, whose slope is the velocity: k4's position part is the
  // candidate's own velocity, so the estimate needs no fourth evaluation; three per step (k1
  // once per step however often it is taken again), two per rejected try.
  const double t = state_.time;
  const Vec3 *x = state_.x.data(), *v = state_.v.data();
  Vec3 *k1v = k1v_.data(), *k2x = k2x_.data(), *k2v = k2v_.data(), *k3x = k3x_.data(), *k3v = k3v_.data();
  Vec3 *xs = xs_.data(), *vs = vs_.data(), *xn = xn_.data(), *vn = vn_.data();
  const double* inv = adaptive_.inverseScale().data();
  accelerations(x, v, t, k1v);
  for (bool rejected = false;; rejected = true) {
    double h = 0.0, wanted = 0.0;
    if (!chooseStep(h, wanted)) return;
    drivers_.over(state_.time, state_.time + h);
    const auto stage = [&](double c, const Vec3* kx, const Vec3* kv, Vec3* nextKx) {
      forVertices([&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
          xs[i] = x[i] + kx[i] * (c * h);
          vs[i] = v[i] + kv[i] * (c * h);
          nextKx[i] = vs[i];
        }
      });
    };
    stage(0.5, v, k1v, k2x);
    accelerations(xs, vs, t + 0.5 * h, k2v);
    stage(0.75, k2x, k2v, k3x);
    accelerations(xs, vs, t + 0.75 * h, k3v);
    // The candidate and its embedded error (positions, relative to the tolerance x body size).
    std::atomic<double> worst{0.0};
    forVertices([&](std::size_t begin, std::size_t end) {
      foldLargest(worst, largestOver(begin, end, [&](std::size_t i) {
                    xn[i] = x[i] + (v[i] * (2.0 / 9.0) + k2x[i] * (1.0 / 3.0) + k3x[i] * (4.0 / 9.0)) * h;
                    vn[i] = v[i] + (k1v[i] * (2.0 / 9.0) + k2v[i] * (1.0 / 3.0) + k3v[i] * (4.0 / 9.0)) * h;
                    const Vec3 e =
                        (v[i] * (-5.0 / 72.0) + k2x[i] * (1.0 / 12.0) + k3x[i] * (1.0 / 9.0) - vn[i] * 0.125) * h;
                    return length(e) * inv[i];
                  }));
    });
    if (judge(h, wanted, worst.load(), rejected)) return;
  }
}

void World::stepAdaptiveVerlet() {
  // Velocity Verlet at a variable step: x1 = x + h v + h^2/2 a0, v1 = v + h/2 (a0 + a1). Its
  // local position error is h^3/6 a'(t) + O(h^4), and a' ~ (a1 - a0) / h, so h^2/6 |a1 - a0|
  // estimates it from the step's own evaluation. One evaluation per step: a1 is the next step's
  // a0 unless a contact between bodies changed the state. Its stable step is 2/omega against
  // Bogacki-Shampine's 1.73/omega for three evaluations, which makes it the cheaper of the two
  // where stability, not accuracy, bounds the step. The static colliders act on the candidate
  // before a1 is evaluated, as in fixed-step Verlet (stepVelocityVerlet).
  const double t = state_.time;
  const Vec3 *x = state_.x.data(), *v = state_.v.data();
  if (!cachedAccelerationValid_) accelerations(x, v, t, k1v_.data());
  const Vec3* a0 = k1v_.data();
  Vec3 *a1 = k2v_.data(), *vs = vs_.data(), *xn = xn_.data(), *vn = vn_.data();
  const double* inv = adaptive_.inverseScale().data();
  const bool contacts = !model_->colliders.empty();
  for (bool rejected = false;; rejected = true) {
    double h = 0.0, wanted = 0.0;
    if (!chooseStep(h, wanted)) return;
    drivers_.over(state_.time, state_.time + h);
    std::atomic<double> impactWorst{0.0};
    forVertices([&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        xn[i] = x[i] + v[i] * h + a0[i] * (0.5 * h * h);
        vs[i] = v[i] + a0[i] * h;  // velocity predictor for the velocity-dependent forces
      }
      if (contacts) foldLargest(impactWorst, collideCandidate(begin, end, h));
    });
    accelerations(xn, vs, t + h, a1);
    std::atomic<double> worst{0.0};
    forVertices([&](std::size_t begin, std::size_t end) {
      foldLargest(worst, largestOver(begin, end, [&](std::size_t i) {
                    // The contacts' change of the predictor carries over to the end velocity.
                    const Vec3 change = vs[i] - (v[i] + a0[i] * h);
                    vn[i] = v[i] + (a0[i] + a1[i]) * (0.5 * h) + change;
                    return length(a1[i] - a0[i]) * (h * h / 6.0) * inv[i];
                  }));
    });
    const double embedded = worst.load(), impact = impactWorst.load();
    if (!std::isnan(embedded) && embedded <= 1.0) {
      // Taken unless an impact says otherwise: a1 becomes the next a0.
      std::swap(k1v_, k2v_);
      cachedAccelerationValid_ = true;
      if (judge(h, wanted, embedded, rejected, impact)) return;
      std::swap(k1v_, k2v_);  // rejected for an impact: a0 is still the step's
      a0 = k1v_.data();
      a1 = k2v_.data();
      continue;
    }
    cachedAccelerationValid_ = false;  // a NaN step is taken as it is; a rejected one keeps a0
    if (judge(h, wanted, embedded, rejected, impact)) return;
  }
}

double World::collideCandidate(std::size_t begin, std::size_t end, double h) {
  // The static colliders on the candidate path x -> xn, with the predictor vs as the velocity;
  // nothing outside the candidate changes (the step may be taken again). Returns the largest
  // impact error (impactMisplacement, as a fraction of the tolerance).
  const Colliders& colliders = model_->colliders;
  const Vec3* x = state_.x.data();
  Vec3 *xn = xn_.data(), *vs = vs_.data();
  const double* inv = adaptive_.inverseScale().data();
  const ColliderPoses* moving = poses();
  double worst = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    candidateHit_[i] = 0;
    if (state_.invMass[i] == 0.0) continue;  // pinned
    if (!colliders.clearAt(xn[i], moving)) {
      const Vec3 before = vs[i];
      const bool resting = restingAt(i);
      ContactHit first;
      if (colliders.resolve(x[i], xn[i], vs[i], resting, &first, moving)) {
        candidateHit_[i] = 1;
        worst = std::max(worst, impactMisplacement(before, first, resting, h) * inv[i]);
      }
    }
    if (dampingLayers_) colliders.dampInLayers(xn[i], vs[i], h);
  }
  return worst;
}


void World::updateStableStep() {
  adaptive_.updateStableStep(*forces_, state_.x, state_.invMass.data(), integrator_, evaluations_);
}

bool World::chooseStep(double& h, double& wanted) {
  return adaptive_.choose(state_.time, drivers_.kinks(), h, wanted);
}

bool World::judge(double h, double wanted, double embedded, bool afterRejection, double impactGiven) {
  double impact = 0.0;
  if (!model_->colliders.empty() && embedded <= 1.0) impact = impactGiven >= 0.0 ? impactGiven : impactError(h);
  double factor = 1.0, error = 1.0;
  if (!adaptive_.judge(h, embedded, impact, factor, error)) return false;
  accept(h, wanted, factor, error, afterRejection);
  return true;
}

void World::accept(double h, double wanted, double factor, double error, bool afterRejection) {
  const bool boundDue = adaptive_.accept(h, wanted, factor, error, afterRejection);
  dt_ = h;
  Vec3 *x = state_.x.data(), *v = state_.v.data();
  const Vec3 *xn = xn_.data(), *vn = vn_.data();
  lastPass([&](std::size_t i) {
    x[i] = xn[i];
    v[i] = vn[i];
  });
  if (boundDue) updateStableStep();
}

double World::impactMisplacement(const Vec3& velocity, const ContactHit& hit, bool resting, double h) const {
  const Vec3 relative = velocity - hit.surfaceVelocity;  // zero for a still collider
  const Vec3 after = contactVelocity(relative, hit.normal, hit.material, model_->colliders.restingSpeed, resting);
  return length(after - relative) * (1.0 - hit.fraction) * h;
}

double World::impactError(double h) const {
  // A vertex that hits a static collider at a fraction s of the step is stopped there and given
  // its new velocity at the end of the step: the velocity change dv comes (1 - s) h late, which
  // misplaces it by about |dv| (1 - s) h. Read-only (the collision itself happens once the step
  // is accepted). Sustained contact counts too: a body pressing into the ground as it lands
  // stops its lowest vertices at every step, which is where most of a landing's error is made.
  const Colliders& colliders = model_->colliders;
  const Vec3 *x = state_.x.data(), *xn = xn_.data(), *vn = vn_.data();
  const double* inv = adaptive_.inverseScale().data();
  std::atomic<double> worst{0.0};
  forVertices([&](std::size_t begin, std::size_t end) {
    foldLargest(worst, largestOver(begin, end, [&](std::size_t i) {
                  if (state_.invMass[i] == 0.0 || colliders.clearAt(xn[i], poses())) return 0.0;
                  ContactHit hit;
                  if (!colliders.firstHit(x[i], xn[i], hit, poses())) return 0.0;
                  return impactMisplacement(vn[i], hit, restingAt(i), h) * inv[i];
                }));
  });
  return worst.load();
}

bool World::savesOldInLastPass() const {
  return integrator_ == Integrator::ExplicitEuler || integrator_ == Integrator::SymplecticEuler ||
         integrator_ == Integrator::RK4 || adaptive();
}

template <class Update>
void World::lastPass(Update&& update) {
  // One fork-join: each thread saves, updates and resolves the contacts of its own vertices
  // (a vertex's contact reads only its own old and new state).
  const bool contacts = !model_->colliders.empty(), saveOld = keepsOld() && savesOldInLastPass();
  std::atomic<bool> touched{false};
  Vec3 *x = state_.x.data(), *xOld = xOld_.data();
  forVertices([&](std::size_t begin, std::size_t end) {
    if (saveOld) std::copy(x + begin, x + end, xOld + begin);
    for (std::size_t i = begin; i < end; ++i) update(i);
    if (contacts && integrator_ == Integrator::AdaptiveVerlet) {
      recordCandidateContacts(begin, end);  // resolved on the candidate (collideCandidate)
    } else if (contacts && collide(begin, end, state_.v.data())) {
      touched.store(true, std::memory_order_relaxed);
    }
  });
  if (touched.load(std::memory_order_relaxed)) cachedAccelerationValid_ = false;
}

void World::recordCandidateContacts(std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    bookContact(i, candidateHit_[i] != 0);
  }
}

void World::bookContact(std::size_t i, bool hit) {
  sinceContact_[i] = hit ? 0 : static_cast<uint16_t>(std::min<int>(sinceContact_[i] + 1, 0xFFFF));
  if (hit && adaptive()) lastContactTime_[i] = state_.time;
}

bool World::collide(std::size_t begin, std::size_t end, Vec3* velocity) {
  const Colliders& colliders = model_->colliders;
  const bool layers = dampingLayers_;
  bool hitAny = false;
  for (std::size_t i = begin; i < end; ++i) {
    if (state_.invMass[i] == 0.0) continue;  // pinned
    const bool hit = !colliders.clearAt(state_.x[i], poses()) &&
                     colliders.resolve(xOld_[i], state_.x[i], velocity[i], restingAt(i), nullptr, poses());
    bookContact(i, hit);
    const bool damped = layers && colliders.dampInLayers(state_.x[i], velocity[i], dt_);
    hitAny = hitAny || hit || damped;
  }
  return hitAny;
}

}  // namespace springy

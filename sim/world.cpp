#include "sim/world.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>

#include "sim/implicit.h"

namespace springy {
namespace {

struct IntegratorEntry {
  Integrator value;
  std::string_view name;
};
constexpr IntegratorEntry kIntegrators[] = {
    {Integrator::ExplicitEuler, "explicit_euler"}, {Integrator::SymplecticEuler, "symplectic_euler"},
    {Integrator::VelocityVerlet, "verlet"},        {Integrator::Leapfrog, "leapfrog"},
    {Integrator::RK4, "rk4"},
    {Integrator::BackwardEuler, "backward_euler"},
};

}  // namespace

std::string_view integratorName(Integrator integrator) {
  for (const IntegratorEntry& e : kIntegrators) {
    if (e.value == integrator) return e.name;
  }
  return "?";
}

bool parseIntegrator(std::string_view name, Integrator& out) {
  for (const IntegratorEntry& e : kIntegrators) {
    if (e.name == name) {
      out = e.value;
      return true;
    }
  }
  return false;
}

std::string integratorNames() {
  std::string s;
  for (const IntegratorEntry& e : kIntegrators) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

World::World(Model model, Integrator integrator, double dt)
    : model_(std::make_unique<Model>(std::move(model))), integrator_(integrator), dt_(dt) {
  assert(dt > 0.0);
  // The model is final once the colliders' trees are built; the force stages read it from here on.
  for (TriangleCollider& tc : model_->colliders.meshes) {
    if (tc.nodes.empty()) tc.buildBvh();
  }
  dampingLayers_ = model_->colliders.dampingLayers();
  forces_ = std::make_unique<Forces>(*model_);
  if (BodyContacts::needed(*model_)) contacts_ = std::make_unique<BodyContacts>(*model_);

  const std::size_t n = model_->vertexCount();
  x_ = model_->restPosition;
  v_ = model_->initialVelocity;
  for (auto* buffer : {&xOld_, &a_}) buffer->assign(n, Vec3{});
  if (!model_->colliders.empty()) sinceContact_.assign(n, 0xFFFF);
  restingSteps_ = static_cast<int>(std::ceil(model_->colliders.restingWindow / dt_));
  if (integrator_ == Integrator::RK4) {
    for (auto* buffer : {&k1v_, &k2x_, &k2v_, &k3x_, &k3v_, &k4v_, &xs_, &vs_}) buffer->assign(n, Vec3{});
  }
  if (integrator_ == Integrator::VelocityVerlet || integrator_ == Integrator::Leapfrog) vs_.assign(n, Vec3{});
  if (integrator_ == Integrator::VelocityVerlet) aNext_.assign(n, Vec3{});
  if (integrator_ == Integrator::BackwardEuler) implicit_ = std::make_unique<ImplicitSolver>(*model_);
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
  x_ = std::move(x);
  v_ = std::move(v);
  time_ = time;
  cachedAccelerationValid_ = false;
  std::fill(sinceContact_.begin(), sinceContact_.end(), 0xFFFF);
}

void World::step() {
  // Contacts need the positions at the start of the step (xOld). The integrators that change
  // x only in their last pass save it there (lastPass); the others save it now.
  if (keepsOld() && !savesOldInLastPass()) {
    Vec3 *x = x_.data(), *xOld = xOld_.data();
    forVertices([&](std::size_t begin, std::size_t end) { std::copy(x + begin, x + end, xOld + begin); });
  }
  // Integrate; every integrator's last pass over the vertices resolves their contacts too.
  switch (integrator_) {
    case Integrator::ExplicitEuler: stepExplicitEuler(); break;
    case Integrator::SymplecticEuler: stepSymplecticEuler(); break;
    case Integrator::VelocityVerlet: stepVelocityVerlet(); break;
    case Integrator::Leapfrog: stepLeapfrog(); break;
    case Integrator::RK4: stepRK4(); break;
    case Integrator::BackwardEuler: stepBackwardEuler(); break;
  }
  // Contact between and within bodies, over the whole step's paths.
  if (contacts_ && contacts_->resolve(xOld_, x_, v_, dt_)) cachedAccelerationValid_ = false;
  time_ += dt_;
  ++steps_;
}

void World::stepExplicitEuler() {
  const double dt = dt_, t = time_;
  Vec3 *x = x_.data(), *v = v_.data(), *a = a_.data();
  accelerations(x, v, t, a);
  lastPass([&](std::size_t i) {
    x[i] += v[i] * dt;
    v[i] += a[i] * dt;
  });
}

void World::stepSymplecticEuler() {
  const double dt = dt_, t = time_;
  Vec3 *x = x_.data(), *v = v_.data(), *a = a_.data();
  accelerations(x, v, t, a);
  lastPass([&](std::size_t i) {
    v[i] += a[i] * dt;
    x[i] += v[i] * dt;
  });
}

void World::stepVelocityVerlet() {
  // a(t) is the a(t + dt) of the previous step unless contact changed the velocities since.
  const double dt = dt_, t = time_;
  Vec3 *x = x_.data(), *v = v_.data(), *a = a_.data(), *vs = vs_.data(), *aNext = aNext_.data();
  if (!cachedAccelerationValid_) accelerations(x, v, t, a);
  forVertices([&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      x[i] += v[i] * dt + a[i] * (0.5 * dt * dt);
      vs[i] = v[i] + a[i] * dt;  // velocity predictor for the velocity-dependent forces
    }
  });
  accelerations(x, vs, t + dt, aNext);
  cachedAccelerationValid_ = true;  // unless a contact changes a velocity in the last pass
  lastPass([&](std::size_t i) {
    v[i] += (a[i] + aNext[i]) * (0.5 * dt);
    a[i] = aNext[i];
  });
}

void World::stepLeapfrog() {
  // Forces at both ends of the step. The closing kick needs a(t + dt) at the velocity
  // v(t + dt), which it is about to compute; the half-step velocity plus the first half
  // kick once more predicts it to O(dt^2), which keeps the scheme second order when the
  // forces depend on velocity (dampers, drag). With position-only forces it is exact KDK.
  const double dt = dt_, t = time_;
  Vec3 *x = x_.data(), *v = v_.data(), *a = a_.data(), *vs = vs_.data();
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
  const double dt = dt_, t = time_;
  Vec3 *x = x_.data(), *v = v_.data();
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
  implicit_->step(*forces_, x_, v_, time_, dt_);
  if (!model_->colliders.empty()) lastPass([](std::size_t) {});  // the static colliders' pass
}

bool World::savesOldInLastPass() const {
  return integrator_ == Integrator::ExplicitEuler || integrator_ == Integrator::SymplecticEuler ||
         integrator_ == Integrator::RK4;
}

template <class Update>
void World::lastPass(Update&& update) {
  // One fork-join: each thread saves, updates and resolves the contacts of its own vertices
  // (a vertex's contact reads only its own old and new state).
  const bool contacts = !model_->colliders.empty(), saveOld = keepsOld() && savesOldInLastPass();
  std::atomic<bool> touched{false};
  Vec3 *x = x_.data(), *xOld = xOld_.data();
  forVertices([&](std::size_t begin, std::size_t end) {
    if (saveOld) std::copy(x + begin, x + end, xOld + begin);
    for (std::size_t i = begin; i < end; ++i) update(i);
    if (contacts && collide(begin, end)) touched.store(true, std::memory_order_relaxed);
  });
  if (touched.load(std::memory_order_relaxed)) cachedAccelerationValid_ = false;
}

bool World::collide(std::size_t begin, std::size_t end) {
  const Colliders& colliders = model_->colliders;
  const bool layers = dampingLayers_;
  bool hitAny = false;
  for (std::size_t i = begin; i < end; ++i) {
    if (model_->invMass[i] == 0.0) continue;  // pinned
    const bool hit =
        !colliders.clearAt(x_[i]) && colliders.resolve(xOld_[i], x_[i], v_[i], sinceContact_[i] <= restingSteps_);
    sinceContact_[i] = hit ? 0 : static_cast<uint16_t>(std::min<int>(sinceContact_[i] + 1, 0xFFFF));
    const bool damped = layers && colliders.dampInLayers(x_[i], v_[i], dt_);
    hitAny = hitAny || hit || damped;
  }
  return hitAny;
}

}  // namespace springy

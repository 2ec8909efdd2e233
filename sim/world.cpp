#include "sim/world.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/implicit.h"
#include "sim/strut.h"

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

// y = a + s b over a whole array.
void axpy(std::vector<Vec3>& y, const std::vector<Vec3>& a, double s, const std::vector<Vec3>& b) {
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = a[i] + b[i] * s;
}

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

std::string_view forceStageName(ForceStage stage) {
  switch (stage) {
    case ForceStage::Gravity: return "gravity";
    case ForceStage::Drag: return "drag";
    case ForceStage::Wind: return "wind";
    case ForceStage::Struts: return "struts";
    case ForceStage::Hinges: return "hinges";
  }
  return "?";
}

World::World(Model model, Integrator integrator, double dt)
    : model_(std::move(model)), integrator_(integrator), dt_(dt) {
  assert(dt > 0.0);
  // Assemble the force stages this scene uses, in a fixed order.
  if (model_.gravity != Vec3{}) forceStages_.push_back(ForceStage::Gravity);
  if (model_.drag > 0.0) forceStages_.push_back(ForceStage::Drag);
  if (model_.wind && model_.wind->pressure > 0.0) forceStages_.push_back(ForceStage::Wind);
  if (!model_.struts.empty()) forceStages_.push_back(ForceStage::Struts);
  if (!model_.hinges.empty()) forceStages_.push_back(ForceStage::Hinges);
  for (TriangleCollider& tc : model_.colliders.meshes) {
    if (tc.nodes.empty()) tc.buildBvh();
  }

  const std::size_t n = model_.vertexCount();
  x_ = model_.restPosition;
  v_ = model_.initialVelocity;
  for (auto* buffer : {&xOld_, &a_, &forceScratch_}) buffer->assign(n, Vec3{});
  if (!model_.colliders.empty()) sinceContact_.assign(n, 0xFFFF);
  restingSteps_ = static_cast<int>(std::ceil(model_.colliders.restingWindow / dt_));
  if (integrator_ == Integrator::RK4) {
    for (auto* buffer : {&k1x_, &k1v_, &k2x_, &k2v_, &k3x_, &k3v_, &k4v_, &xs_, &vs_}) buffer->assign(n, Vec3{});
  }
  if (integrator_ == Integrator::VelocityVerlet || integrator_ == Integrator::Leapfrog) vs_.assign(n, Vec3{});
  if (integrator_ == Integrator::VelocityVerlet) aNext_.assign(n, Vec3{});
  if (integrator_ == Integrator::BackwardEuler) implicit_ = std::make_unique<ImplicitSolver>(model_);
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

void World::setState(std::vector<Vec3> x, std::vector<Vec3> v, double time) {
  assert(x.size() == model_.vertexCount() && v.size() == model_.vertexCount());
  x_ = std::move(x);
  v_ = std::move(v);
  time_ = time;
  cachedAccelerationValid_ = false;
  std::fill(sinceContact_.begin(), sinceContact_.end(), 0xFFFF);
}

void World::computeForces(const Vec3* x, const Vec3* v, double t, Vec3* f) const {
  const std::size_t n = model_.vertexCount();
  std::fill(f, f + n, Vec3{});
  const Vec3 air = model_.wind ? model_.wind->airVelocity(t) : Vec3{};
  for (ForceStage stage : forceStages_) {
    switch (stage) {
      case ForceStage::Gravity: applyGravity(model_, 0, n, f); break;
      case ForceStage::Drag: applyDrag(model_, 0, n, air, v, f); break;
      case ForceStage::Wind: applyWindPressure(model_, 0, model_.faces.size(), air, x, v, f); break;
      case ForceStage::Struts: applyStruts(model_.struts.data(), 0, model_.struts.size(), x, v, f); break;
      case ForceStage::Hinges: applyHinges(model_.hinges.data(), 0, model_.hinges.size(), x, v, f); break;
    }
  }
}

void World::accelerations(const Vec3* x, const Vec3* v, double t, Vec3* a) const {
  computeForces(x, v, t, forceScratch_.data());
  const std::size_t n = model_.vertexCount();
  for (std::size_t i = 0; i < n; ++i) a[i] = forceScratch_[i] * model_.invMass[i];  // pinned: invMass 0
}

void World::step() {
  const std::size_t n = model_.vertexCount();
  const double dt = dt_, t = time_;
  if (!model_.colliders.empty()) xOld_ = x_;

  switch (integrator_) {
    case Integrator::ExplicitEuler:
      accelerations(x_.data(), v_.data(), t, a_.data());
      for (std::size_t i = 0; i < n; ++i) {
        x_[i] += v_[i] * dt;
        v_[i] += a_[i] * dt;
      }
      break;
    case Integrator::SymplecticEuler:
      accelerations(x_.data(), v_.data(), t, a_.data());
      for (std::size_t i = 0; i < n; ++i) {
        v_[i] += a_[i] * dt;
        x_[i] += v_[i] * dt;
      }
      break;
    case Integrator::VelocityVerlet:
      // a(t) is the a(t + dt) of the previous step unless contact changed the velocities since.
      if (!cachedAccelerationValid_) accelerations(x_.data(), v_.data(), t, a_.data());
      for (std::size_t i = 0; i < n; ++i) {
        x_[i] += v_[i] * dt + a_[i] * (0.5 * dt * dt);
        vs_[i] = v_[i] + a_[i] * dt;  // velocity predictor for the velocity-dependent forces
      }
      accelerations(x_.data(), vs_.data(), t + dt, aNext_.data());
      for (std::size_t i = 0; i < n; ++i) {
        v_[i] += (a_[i] + aNext_[i]) * (0.5 * dt);
        a_[i] = aNext_[i];
      }
      cachedAccelerationValid_ = true;
      break;
    case Integrator::Leapfrog:
      // Forces at both ends of the step. The closing kick needs a(t + dt) at the velocity
      // v(t + dt), which it is about to compute; the half-step velocity plus the first half
      // kick once more predicts it to O(dt^2), which keeps the scheme second order when the
      // forces depend on velocity (dampers, drag). With position-only forces it is exact KDK.
      accelerations(x_.data(), v_.data(), t, a_.data());
      for (std::size_t i = 0; i < n; ++i) {
        v_[i] += a_[i] * (0.5 * dt);           // kick
        x_[i] += v_[i] * dt;                   // drift
        vs_[i] = v_[i] + a_[i] * (0.5 * dt);   // predicted v(t + dt)
      }
      accelerations(x_.data(), vs_.data(), t + dt, a_.data());
      for (std::size_t i = 0; i < n; ++i) v_[i] += a_[i] * (0.5 * dt);  // kick
      break;
    case Integrator::RK4: {
      // k1 = f(y), k2 = f(y + dt/2 k1), k3 = f(y + dt/2 k2), k4 = f(y + dt k3); the position
      // slopes are the stage velocities, the velocity slopes the stage accelerations.
      k1x_ = v_;
      accelerations(x_.data(), v_.data(), t, k1v_.data());
      axpy(xs_, x_, 0.5 * dt, k1x_);
      axpy(vs_, v_, 0.5 * dt, k1v_);
      k2x_ = vs_;
      accelerations(xs_.data(), vs_.data(), t + 0.5 * dt, k2v_.data());
      axpy(xs_, x_, 0.5 * dt, k2x_);
      axpy(vs_, v_, 0.5 * dt, k2v_);
      k3x_ = vs_;
      accelerations(xs_.data(), vs_.data(), t + 0.5 * dt, k3v_.data());
      axpy(xs_, x_, dt, k3x_);
      axpy(vs_, v_, dt, k3v_);
      accelerations(xs_.data(), vs_.data(), t + dt, k4v_.data());
      const double w = dt / 6.0;
      for (std::size_t i = 0; i < n; ++i) {
        // k4x = vs_ (the fourth stage's velocity).
        x_[i] += (k1x_[i] + (k2x_[i] + k3x_[i]) * 2.0 + vs_[i]) * w;
        v_[i] += (k1v_[i] + (k2v_[i] + k3v_[i]) * 2.0 + k4v_[i]) * w;
      }
      break;
    }
    case Integrator::BackwardEuler:
      implicit_->step(*this, x_, v_, t, dt);
      break;
  }
  time_ = t + dt;
  ++steps_;
  if (!model_.colliders.empty()) collide();
}

void World::collide() {
  const Colliders& colliders = model_.colliders;
  bool touched = false;
  const std::size_t n = model_.vertexCount();
  for (std::size_t i = 0; i < n; ++i) {
    if (model_.invMass[i] == 0.0) continue;  // pinned
    const bool hit = colliders.resolve(xOld_[i], x_[i], v_[i], sinceContact_[i] <= restingSteps_);
    sinceContact_[i] = hit ? 0 : static_cast<uint16_t>(std::min<int>(sinceContact_[i] + 1, 0xFFFF));
    touched = touched || hit;
  }
  if (touched) cachedAccelerationValid_ = false;
}

}  // namespace springy

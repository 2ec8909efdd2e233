#include "sim/world.h"

#include <algorithm>
#include <atomic>
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
    case ForceStage::Gas: return "gas";
    case ForceStage::Deformation: return "deformation damping";
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
  for (uint32_t b = 0; b < model_.bodies.size(); ++b) {
    const BodyInfo& info = model_.bodies[b];
    if (!(info.gasPressure > 0.0)) continue;
    gasBodies_.push_back(b);
    const uint32_t end = info.firstFace + info.faceCount;
    for (uint32_t f = info.firstFace; f < end; f += kVolumeChunk) {
      volumeChunks_.push_back({b, f, std::min(f + kVolumeChunk, end)});
    }
  }
  chunkSum_.assign(volumeChunks_.size(), 0.0);
  if (!gasBodies_.empty()) {
    forceStages_.push_back(ForceStage::Gas);
    overpressure_.assign(model_.bodies.size(), 0.0);
    areaVectors_.assign(model_.faces.size(), Vec3{});
    facesAround_ = vertexFaces(model_);
  }
  rigid_.assign(model_.bodies.size(), RigidMotion{});
  for (uint32_t b = 0; b < model_.bodies.size(); ++b) {
    const BodyInfo& info = model_.bodies[b];
    if (!(info.deformationDamping > 0.0)) continue;
    rigid_[b].rate = info.deformationDamping;
    const uint32_t end = info.firstVertex + info.vertexCount;
    for (uint32_t i = info.firstVertex; i < end; i += kVolumeChunk) {
      rigidChunks_.push_back({b, i, std::min(i + kVolumeChunk, end)});
    }
  }
  chunkMoments_.assign(rigidChunks_.size(), MassMoments{});
  if (!rigidChunks_.empty()) forceStages_.push_back(ForceStage::Deformation);
  for (TriangleCollider& tc : model_.colliders.meshes) {
    if (tc.nodes.empty()) tc.buildBvh();
  }
  dampingLayers_ = model_.colliders.dampingLayers();

  const std::size_t n = model_.vertexCount();
  x_ = model_.restPosition;
  v_ = model_.initialVelocity;
  for (auto* buffer : {&xOld_, &a_}) buffer->assign(n, Vec3{});
  if (!model_.colliders.empty()) sinceContact_.assign(n, 0xFFFF);
  restingSteps_ = static_cast<int>(std::ceil(model_.colliders.restingWindow / dt_));
  if (integrator_ == Integrator::RK4) {
    for (auto* buffer : {&k1v_, &k2x_, &k2v_, &k3x_, &k3v_, &k4v_, &xs_, &vs_}) buffer->assign(n, Vec3{});
  }
  if (integrator_ == Integrator::VelocityVerlet || integrator_ == Integrator::Leapfrog) vs_.assign(n, Vec3{});
  if (integrator_ == Integrator::VelocityVerlet) aNext_.assign(n, Vec3{});
  if (integrator_ == Integrator::BackwardEuler) implicit_ = std::make_unique<ImplicitSolver>(model_);
  hingeTerms_.reserve(model_.hinges.size());
  for (const Hinge& h : model_.hinges) hingeTerms_.push_back(hingeTerms(h));
}

void World::setThreads(unsigned requested, std::size_t minVerticesPerThread) {
  const std::size_t n = model_.vertexCount();
  unsigned threads = std::max(1u, requested);
  if (minVerticesPerThread > 0) {
    threads = static_cast<unsigned>(std::min<std::size_t>(threads, std::max<std::size_t>(1, n / minVerticesPerThread)));
  }
  threads = static_cast<unsigned>(std::min<std::size_t>(threads, std::max<std::size_t>(1, n)));
  pool_.reset();
  shares_.clear();
  if (threads <= 1) return;

  // Owners: contiguous index ranges, the ones forVertices hands out. addBody numbers each
  // body's vertices in spatial order, so a range is a compact piece of a body: few elements
  // straddle two owners, and each thread writes its own stretch of memory.
  shares_.resize(threads);
  for (unsigned t = 0; t < threads; ++t) shares_[t].begin = n * t / threads, shares_[t].end = n * (t + 1) / threads;
  // Each thread lists, in index order, the elements with at least one vertex it owns.
  const auto distribute = [&](auto&& vertexOf, std::size_t count, int corners, auto member) {
    for (std::size_t e = 0; e < count; ++e) {
      for (unsigned t = 0; t < threads; ++t) {
        uint32_t mask = 0;
        for (int c = 0; c < corners; ++c) {
          const std::size_t i = vertexOf(e, c);
          if (i >= shares_[t].begin && i < shares_[t].end) mask |= 1u << c;
        }
        if (mask != 0) (shares_[t].*member).push_back({static_cast<uint32_t>(e), mask});
      }
    }
  };
  distribute([&](std::size_t e, int c) { return c == 0 ? model_.struts[e].i : model_.struts[e].j; },
             model_.struts.size(), 2, &Share::struts);
  distribute([&](std::size_t e, int c) { return model_.hinges[e].v[c]; }, model_.hinges.size(), 4, &Share::hinges);
  if (model_.wind || !gasBodies_.empty()) {
    distribute([&](std::size_t e, int c) { return model_.faces[e][static_cast<std::size_t>(c)]; }, model_.faces.size(),
               3, &Share::faces);
  }
  // The other threads' vertices each thread reads (its elements' corners it does not own).
  for (Share& share : shares_) {
    std::vector<uint32_t> foreign;
    const auto add = [&](uint32_t i) {
      if (i < share.begin || i >= share.end) foreign.push_back(i);
    };
    for (const ElementRef& r : share.struts) add(model_.struts[r.index].i), add(model_.struts[r.index].j);
    for (const ElementRef& r : share.hinges) {
      for (uint32_t i : model_.hinges[r.index].v) add(i);
    }
    for (const ElementRef& r : share.faces) {
      for (uint32_t i : model_.faces[r.index]) add(i);
    }
    std::sort(foreign.begin(), foreign.end());
    foreign.erase(std::unique(foreign.begin(), foreign.end()), foreign.end());
    share.foreign = std::move(foreign);
  }
  pool_ = std::make_unique<ThreadPool>(threads);
}

void World::prefetchForeign(unsigned thread, const Vec3* x, const Vec3* v) const {
  // Reading a vertex another core has just written costs a cache-line transfer between the
  // cores (0.06-0.24 us one way on the 2-core VM of docs/benchmarks.md). Met one by one inside
  // the force loops these transfers would add up; requested together up front they overlap.
  for (uint32_t i : shares_[thread].foreign) {
    __builtin_prefetch(&x[i]);
    if (v != nullptr) __builtin_prefetch(&v[i]);
  }
}

double World::redundancy() const {
  if (!pool_) return 1.0;
  std::size_t listed = 0, total = model_.struts.size() + model_.hinges.size();
  for (const Share& share : shares_) listed += share.struts.size() + share.hinges.size();
  return total == 0 ? 1.0 : static_cast<double>(listed) / static_cast<double>(total);
}

template <class F>
void World::forVertices(F&& fn) const {
  parallelFor(model_.vertexCount(), fn);
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

void World::updateGas(const Vec3* x) const {
  if (gasBodies_.empty()) return;
  const auto sumChunks = [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      const VolumeChunk& chunk = volumeChunks_[c];
      chunkSum_[c] = sixVolume(model_, chunk.begin, chunk.end, x[model_.bodies[chunk.body].firstVertex], x,
                               areaVectors_.data());
    }
  };
  if (pool_ && volumeChunks_.size() > 1) {
    pool_->run([&](unsigned thread) {
      prefetchForeign(thread, x, nullptr);
      const std::size_t chunks = volumeChunks_.size(), threads = pool_->size();
      sumChunks(chunks * thread / threads, chunks * (thread + 1) / threads);
    });
  } else {
    sumChunks(0, volumeChunks_.size());
  }
  std::size_t c = 0;
  for (uint32_t b : gasBodies_) {
    double sum = 0.0;
    for (; c < volumeChunks_.size() && volumeChunks_[c].body == b; ++c) sum += chunkSum_[c];
    overpressure_[b] = gasOverpressure(model_.bodies[b], sum / 6.0);
  }
}

void World::updateRigid(const Vec3* x, const Vec3* v) const {
  if (rigidChunks_.empty()) return;
  const auto sumChunks = [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      const VertexChunk& chunk = rigidChunks_[c];
      chunkMoments_[c] = massMoments(model_, chunk.begin, chunk.end, x[model_.bodies[chunk.body].firstVertex], x, v);
    }
  };
  if (pool_ && rigidChunks_.size() > 1) {
    pool_->run([&](unsigned thread) {
      const std::size_t chunks = rigidChunks_.size(), threads = pool_->size();
      sumChunks(chunks * thread / threads, chunks * (thread + 1) / threads);
    });
  } else {
    sumChunks(0, rigidChunks_.size());
  }
  for (std::size_t c = 0; c < rigidChunks_.size();) {
    const uint32_t b = rigidChunks_[c].body;
    MassMoments sum;
    for (; c < rigidChunks_.size() && rigidChunks_[c].body == b; ++c) sum.add(chunkMoments_[c]);
    const double rate = rigid_[b].rate;
    rigid_[b] = rigidMotion(sum, x[model_.bodies[b].firstVertex]);
    rigid_[b].rate = rate;
  }
}

void World::computeForces(const Vec3* x, const Vec3* v, double t, Vec3* f) const {
  const Vec3 air = model_.wind ? model_.wind->airVelocity(t) : Vec3{};
  prepareForces(x, v);
  if (pool_) {
    pool_->run([&](unsigned thread) { ownedForces(thread, x, v, air, f, false); });
    return;
  }
  const std::size_t n = model_.vertexCount();
  if (!startsWithGravity()) std::fill(f, f + n, Vec3{});
  for (ForceStage stage : forceStages_) {
    switch (stage) {
      case ForceStage::Gravity: setGravity(model_, 0, n, f); break;
      case ForceStage::Drag: applyDrag(model_, 0, n, air, v, f); break;
      case ForceStage::Wind: applyWindPressure(model_, 0, model_.faces.size(), air, x, v, f); break;
      case ForceStage::Struts: applyStruts(model_.struts.data(), 0, model_.struts.size(), x, v, f); break;
      case ForceStage::Hinges:
        applyHinges(model_.hinges.data(), hingeTerms_.data(), 0, model_.hinges.size(), x, v, f);
        break;
      case ForceStage::Gas:
        applyGasPressure(model_, overpressure_.data(), facesAround_, areaVectors_.data(), 0, n, f);
        break;
      case ForceStage::Deformation: applyDeformationDamping(model_, rigid_.data(), 0, n, x, v, f); break;
    }
  }
}

void World::ownedForces(unsigned thread, const Vec3* x, const Vec3* v, const Vec3& air, Vec3* f,
                        bool toAcceleration) const {
  // The same stages in the same order as the one-threaded loop, restricted to this thread's
  // vertices: each vertex receives the same terms in the same order.
  const Share& share = shares_[thread];
  prefetchForeign(thread, x, v);
  if (!startsWithGravity()) std::fill(f + share.begin, f + share.end, Vec3{});
  for (ForceStage stage : forceStages_) {
    switch (stage) {
      case ForceStage::Gravity: setGravity(model_, share.begin, share.end, f); break;
      case ForceStage::Drag: applyDrag(model_, share.begin, share.end, air, v, f); break;
      case ForceStage::Wind: applyWindPressureOwned(model_, share.faces.data(), share.faces.size(), air, x, v, f); break;
      case ForceStage::Struts: applyStrutsOwned(model_.struts.data(), share.struts.data(), share.struts.size(), x, v, f); break;
      case ForceStage::Hinges:
        applyHingesOwned(model_.hinges.data(), hingeTerms_.data(), share.hinges.data(), share.hinges.size(), x, v, f);
        break;
      case ForceStage::Gas:
        applyGasPressure(model_, overpressure_.data(), facesAround_, areaVectors_.data(), share.begin, share.end, f);
        break;
      case ForceStage::Deformation:
        applyDeformationDamping(model_, rigid_.data(), share.begin, share.end, x, v, f);
        break;
    }
  }
  if (toAcceleration) {
    for (std::size_t i = share.begin; i < share.end; ++i) f[i] = f[i] * model_.invMass[i];  // pinned: invMass 0
  }
}

void World::accelerations(const Vec3* x, const Vec3* v, double t, Vec3* a) const {
  if (pool_) {
    const Vec3 air = model_.wind ? model_.wind->airVelocity(t) : Vec3{};
    prepareForces(x, v);
    pool_->run([&](unsigned thread) { ownedForces(thread, x, v, air, a, true); });
    return;
  }
  computeForces(x, v, t, a);
  const std::size_t n = model_.vertexCount();
  for (std::size_t i = 0; i < n; ++i) a[i] = a[i] * model_.invMass[i];  // pinned: invMass 0
}

void World::step() {
  const double dt = dt_, t = time_;
  Vec3 *x = x_.data(), *v = v_.data(), *a = a_.data();
  // Contacts need the positions at the start of the step (xOld). The integrators that change
  // x only in their last pass save it there (lastPass); the others save it now.
  if (!model_.colliders.empty() && !savesOldInLastPass()) {
    Vec3* xOld = xOld_.data();
    forVertices([&](std::size_t begin, std::size_t end) { std::copy(x + begin, x + end, xOld + begin); });
  }

  switch (integrator_) {
    case Integrator::ExplicitEuler:
      accelerations(x, v, t, a);
      lastPass([&](std::size_t i) {
        x[i] += v[i] * dt;
        v[i] += a[i] * dt;
      });
      break;
    case Integrator::SymplecticEuler:
      accelerations(x, v, t, a);
      lastPass([&](std::size_t i) {
        v[i] += a[i] * dt;
        x[i] += v[i] * dt;
      });
      break;
    case Integrator::VelocityVerlet: {
      // a(t) is the a(t + dt) of the previous step unless contact changed the velocities since.
      Vec3 *vs = vs_.data(), *aNext = aNext_.data();
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
      break;
    }
    case Integrator::Leapfrog: {
      // Forces at both ends of the step. The closing kick needs a(t + dt) at the velocity
      // v(t + dt), which it is about to compute; the half-step velocity plus the first half
      // kick once more predicts it to O(dt^2), which keeps the scheme second order when the
      // forces depend on velocity (dampers, drag). With position-only forces it is exact KDK.
      Vec3* vs = vs_.data();
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
      break;
    }
    case Integrator::RK4: {
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
      break;
    }
    case Integrator::BackwardEuler:
      implicit_->step(*this, x_, v_, t, dt);
      if (!model_.colliders.empty()) lastPass([](std::size_t) {});
      break;
  }
  time_ = t + dt;
  ++steps_;
}

bool World::savesOldInLastPass() const {
  return integrator_ == Integrator::ExplicitEuler || integrator_ == Integrator::SymplecticEuler ||
         integrator_ == Integrator::RK4;
}

template <class Update>
void World::lastPass(Update&& update) {
  // One fork-join: each thread saves, updates and resolves the contacts of its own vertices
  // (a vertex's contact reads only its own old and new state).
  const bool contacts = !model_.colliders.empty(), saveOld = savesOldInLastPass();
  std::atomic<bool> touched{false};
  Vec3 *x = x_.data(), *xOld = xOld_.data();
  forVertices([&](std::size_t begin, std::size_t end) {
    if (contacts && saveOld) std::copy(x + begin, x + end, xOld + begin);
    for (std::size_t i = begin; i < end; ++i) update(i);
    if (contacts && collide(begin, end)) touched.store(true, std::memory_order_relaxed);
  });
  if (touched.load(std::memory_order_relaxed)) cachedAccelerationValid_ = false;
}

bool World::collide(std::size_t begin, std::size_t end) {
  const Colliders& colliders = model_.colliders;
  const bool layers = dampingLayers_;
  bool hitAny = false;
  for (std::size_t i = begin; i < end; ++i) {
    if (model_.invMass[i] == 0.0) continue;  // pinned
    const bool hit =
        !colliders.clearAt(x_[i]) && colliders.resolve(xOld_[i], x_[i], v_[i], sinceContact_[i] <= restingSteps_);
    sinceContact_[i] = hit ? 0 : static_cast<uint16_t>(std::min<int>(sinceContact_[i] + 1, 0xFFFF));
    const bool damped = layers && colliders.dampInLayers(x_[i], v_[i], dt_);
    hitAny = hitAny || hit || damped;
  }
  return hitAny;
}

}  // namespace springy

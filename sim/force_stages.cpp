#include "sim/force_stages.h"

#include <algorithm>
#include <iterator>
#include <type_traits>

#include "sim/strut.h"

namespace springy {

Forces::Forces(const Model& model) : model_(&model), invMass_(model.invMass.data()) {
  // The stages' data: the hinges' constants, the gas bodies' face chunks, the damped bodies'
  // vertex chunks.
  data_.hingeTerms.reserve(model_->hinges.size());
  for (const Hinge& h : model_->hinges) data_.hingeTerms.push_back(hingeTerms(h));
  for (uint32_t b = 0; b < model_->bodies.size(); ++b) {
    const BodyInfo& info = model_->bodies[b];
    if (!(info.gasPressure > 0.0)) continue;
    data_.gasBodies.push_back(b);
    const uint32_t end = info.firstFace + info.faceCount;
    for (uint32_t f = info.firstFace; f < end; f += kVolumeChunk) {
      volumeChunks_.push_back({b, f, std::min(f + kVolumeChunk, end)});
    }
  }
  chunkSum_.assign(volumeChunks_.size(), 0.0);
  if (!data_.gasBodies.empty()) {
    data_.overpressure.assign(model_->bodies.size(), 0.0);
    data_.areaVectors.assign(model_->faces.size(), Vec3{});
    data_.facesAround = vertexFaces(*model_);
  }
  data_.rigid.assign(model_->bodies.size(), RigidMotion{});
  for (uint32_t b = 0; b < model_->bodies.size(); ++b) {
    const BodyInfo& info = model_->bodies[b];
    if (!(info.deformationDamping > 0.0)) continue;
    data_.rigid[b].rate = info.deformationDamping;
    const uint32_t end = info.firstVertex + info.vertexCount;
    for (uint32_t i = info.firstVertex; i < end; i += kVolumeChunk) {
      rigidChunks_.push_back({b, i, std::min(i + kVolumeChunk, end)});
    }
  }
  chunkMoments_.assign(rigidChunks_.size(), MassMoments{});
  data_.damped = !rigidChunks_.empty();
  // The stages this model uses, in the registry's order.
  stages_ = stagesOf(*model_);
}


void Forces::setThreads(unsigned requested, std::size_t minVerticesPerThread) {
  const std::size_t n = model_->vertexCount();
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
  distribute([&](std::size_t e, int c) { return c == 0 ? model_->struts[e].i : model_->struts[e].j; },
             model_->struts.size(), 2, &Share::struts);
  distribute([&](std::size_t e, int c) { return model_->hinges[e].v[c]; }, model_->hinges.size(), 4, &Share::hinges);
  if (model_->wind || !data_.gasBodies.empty()) {
    distribute([&](std::size_t e, int c) { return model_->faces[e][static_cast<std::size_t>(c)]; }, model_->faces.size(),
               3, &Share::faces);
  }
  // The other threads' vertices each thread reads (its elements' corners it does not own).
  for (Share& share : shares_) {
    std::vector<uint32_t> foreign;
    const auto add = [&](uint32_t i) {
      if (i < share.begin || i >= share.end) foreign.push_back(i);
    };
    for (const ElementRef& r : share.struts) add(model_->struts[r.index].i), add(model_->struts[r.index].j);
    for (const ElementRef& r : share.hinges) {
      for (uint32_t i : model_->hinges[r.index].v) add(i);
    }
    for (const ElementRef& r : share.faces) {
      for (uint32_t i : model_->faces[r.index]) add(i);
    }
    std::sort(foreign.begin(), foreign.end());
    foreign.erase(std::unique(foreign.begin(), foreign.end()), foreign.end());
    share.foreign = std::move(foreign);
  }
  pool_ = std::make_unique<ThreadPool>(threads);
}


void Forces::prefetchForeign(unsigned thread, const Vec3* x, const Vec3* v) const {
  // Reading a vertex another core has just written costs a cache-line transfer between the
  // cores (0.06-0.24 us one way on the 2-core VM of docs/benchmarks.md). Met one by one inside
  // the force loops these transfers would add up; requested together up front they overlap.
  for (uint32_t i : shares_[thread].foreign) {
    __builtin_prefetch(&x[i]);
    if (v != nullptr) __builtin_prefetch(&v[i]);
  }
}


double Forces::redundancy() const {
  if (!pool_) return 1.0;
  std::size_t listed = 0, total = model_->struts.size() + model_->hinges.size();
  for (const Share& share : shares_) listed += share.struts.size() + share.hinges.size();
  return total == 0 ? 1.0 : static_cast<double>(listed) / static_cast<double>(total);
}


void Forces::updateGas(const Vec3* x) const {
  if (data_.gasBodies.empty()) return;
  const auto sumChunks = [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      const VolumeChunk& chunk = volumeChunks_[c];
      chunkSum_[c] = sixVolume(*model_, chunk.begin, chunk.end, x[model_->bodies[chunk.body].firstVertex], x,
                               data_.areaVectors.data());
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
  for (uint32_t b : data_.gasBodies) {
    double sum = 0.0;
    for (; c < volumeChunks_.size() && volumeChunks_[c].body == b; ++c) sum += chunkSum_[c];
    data_.overpressure[b] = gasOverpressure(model_->bodies[b], sum / 6.0);
  }
}


void Forces::updateRigid(const Vec3* x, const Vec3* v) const {
  if (rigidChunks_.empty()) return;
  const auto sumChunks = [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      const VertexChunk& chunk = rigidChunks_[c];
      chunkMoments_[c] = massMoments(*model_, chunk.begin, chunk.end, x[model_->bodies[chunk.body].firstVertex], x, v);
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
    const double rate = data_.rigid[b].rate;
    data_.rigid[b] = rigidMotion(sum, x[model_->bodies[b].firstVertex]);
    data_.rigid[b].rate = rate;
  }
}


void Forces::evaluate(const Vec3* x, const Vec3* v, double t, Vec3* f) const {
  const Vec3 air = model_->wind ? model_->wind->airVelocity(t) : Vec3{};
  prepare(x, v);
  if (pool_) {
    pool_->run([&](unsigned thread) { ownedForces(thread, x, v, air, f, false); });
    return;
  }
  runStages(Everything{0, model_->vertexCount()}, x, v, air, f);
}

void Forces::ownedForces(unsigned thread, const Vec3* x, const Vec3* v, const Vec3& air, Vec3* f,
                         bool toAcceleration) const {
  const Share& share = shares_[thread];
  prefetchForeign(thread, x, v);
  runStages(share, x, v, air, f);
  if (toAcceleration) {
    for (std::size_t i = share.begin; i < share.end; ++i) f[i] = f[i] * invMass_[i];  // pinned: invMass 0
  }
}

template <class Scope>
void Forces::runStages(const Scope& scope, const Vec3* x, const Vec3* v, const Vec3& air, Vec3* f) const {
  // One thread: every vertex and element. A thread's share: its own vertices, from the elements
  // that touch them, in the same stages and order, so each vertex receives the same terms in the
  // same order on every thread count.
  const Model& m = *model_;
  const auto elementsOf = [&](std::vector<ElementRef> Share::*list, std::size_t all) {
    if constexpr (std::is_same_v<Scope, Everything>) {
      return Elements::range(0, all);
    } else {
      return Elements::owned(scope.*list);
    }
  };
  const StageCall call{m,
                       data_,
                       x,
                       v,
                       air,
                       f,
                       scope.begin,
                       scope.end,
                       elementsOf(&Share::struts, m.struts.size()),
                       elementsOf(&Share::hinges, m.hinges.size()),
                       elementsOf(&Share::faces, m.faces.size())};
  if (!startsWithGravity()) std::fill(f + scope.begin, f + scope.end, Vec3{});
  for (ForceStage stage : stages_) forceKind(stage).force(call);
}

void Forces::accelerations(const Vec3* x, const Vec3* v, double t, Vec3* a) const {
  if (pool_) {
    const Vec3 air = model_->wind ? model_->wind->airVelocity(t) : Vec3{};
    prepare(x, v);
    pool_->run([&](unsigned thread) { ownedForces(thread, x, v, air, a, true); });
    return;
  }
  evaluate(x, v, t, a);
  const std::size_t n = model_->vertexCount();
  for (std::size_t i = 0; i < n; ++i) a[i] = a[i] * invMass_[i];  // pinned: invMass 0
}

}  // namespace springy

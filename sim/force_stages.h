// springy: the force stages of a model, evaluated for any state: what World's integrators and
// the implicit solver call for f(x, v, t).
//
// The stage list is assembled once from the model, in a fixed order, and holds only what the
// scene uses (no wind stage without wind, no hinge stage for the legacy all-pairs model):
//   [gravity] [drag] [wind] [struts] [hinges] [gas] [deformation damping]
// Each kind is a row of the registry (sim/force_kinds.h), which names its kernel: over vertices it
// takes a range, over elements an Elements selection (all of them, or a thread's list;
// sim/parallel.h).
//
// Threads (setThreads): the evaluation is split by vertex ownership (each thread computes the
// forces on its own contiguous range of vertices from the elements that touch them), and the
// per-body sums (the gas's volume, the deformation damping's moments) in fixed chunks summed in
// order, so every thread count gives bit-identical results. All scratch is allocated here, once.
#pragma once

#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "sim/force_kinds.h"
#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/model.h"
#include "sim/parallel.h"

namespace springy {

class Forces {
 public:
  // Reads `model` (which must outlive this object and not move) at every evaluation.
  explicit Forces(const Model& model);

  // Total force on every vertex for a state (x, v) at time t, running the stage list.
  void evaluate(const Vec3* x, const Vec3* v, double t, Vec3* f) const;
  // The same divided by the masses (0 for pinned vertices).
  void accelerations(const Vec3* x, const Vec3* v, double t, Vec3* a) const;

  const std::vector<ForceStage>& stages() const { return stages_; }
  const Model& model() const { return *model_; }
  // The inverse masses accelerations() divides by (the World's, which a pin's release changes;
  // the model's until set), and must outlive this object.
  void setInverseMasses(const double* invMass) { invMass_ = invMass; }
  const double* inverseMasses() const { return invMass_; }

  // Up to `requested` threads (the calling thread included), fewer when the model has under
  // `minVerticesPerThread` vertices per thread (see World::kMinVerticesPerThread).
  void setThreads(unsigned requested, std::size_t minVerticesPerThread);
  unsigned threads() const { return pool_ ? pool_->size() : 1; }
  // Elements evaluated per evaluation over all threads, divided by the element count.
  double redundancy() const;
  // Runs fn(begin, end) over [0, n) split into contiguous ranges among the threads.
  template <class F>
  void parallelFor(std::size_t n, F&& fn) const {
    if (pool_) pool_->forRange(n, fn);
    else fn(std::size_t{0}, n);
  }

 private:
  // Gravity, when present, is the first stage and writes the forces; otherwise they start at 0.
  bool startsWithGravity() const { return !stages_.empty() && stages_[0] == ForceStage::Gravity; }
  // One thread's share of an evaluation: the forces on its own vertices (a contiguous range),
  // optionally divided by the masses, written to f. Threads write disjoint ranges.
  void ownedForces(unsigned thread, const Vec3* x, const Vec3* v, const Vec3& air, Vec3* f,
                   bool toAcceleration) const;
  // The stage loop over the registry: Scope is Everything (one thread) or a thread's Share (its
  // vertices and the elements that touch them).
  struct Everything {
    std::size_t begin, end;
  };
  template <class Scope>
  void runStages(const Scope& scope, const Vec3* x, const Vec3* v, const Vec3& air, Vec3* f) const;
  // The per-body sums the stages need before the forces: each gas body's volume and
  // overpressure (chunks of faces summed by the threads, then the chunks' sums in order), and
  // each damped body's rigid motion (chunks of vertices likewise).
  void updateGas(const Vec3* x) const;
  void updateRigid(const Vec3* x, const Vec3* v) const;
  void prepare(const Vec3* x, const Vec3* v) const {
    updateGas(x);
    updateRigid(x, v);
  }
  // Asks for the positions (and velocities, if v is not null) of the vertices thread `thread`
  // reads but does not own, ahead of the loops that read them.
  void prefetchForeign(unsigned thread, const Vec3* x, const Vec3* v) const;

  // A thread's share: the vertices it owns, [begin, end), the elements that touch them, and
  // the other vertices of those elements (sorted).
  struct Share {
    std::size_t begin = 0, end = 0;
    std::vector<ElementRef> struts, hinges, faces;
    std::vector<uint32_t> foreign;
  };

  const Model* model_;
  const double* invMass_;
  std::vector<ForceStage> stages_;
  mutable StageData data_;  // the per-evaluation parts change in prepare()
  struct VolumeChunk {
    uint32_t body, begin, end;  // faces [begin, end) of a gas body
  };
  std::vector<VolumeChunk> volumeChunks_;      // in body and face order
  mutable std::vector<double> chunkSum_;       // per chunk: six times its volume
  struct VertexChunk {
    uint32_t body, begin, end;  // vertices [begin, end) of a body with deformation damping
  };
  std::vector<VertexChunk> rigidChunks_;        // in body and vertex order
  mutable std::vector<MassMoments> chunkMoments_;  // per chunk, for the evaluation under way
  std::unique_ptr<ThreadPool> pool_;           // null: one thread
  std::vector<Share> shares_;                  // one per thread when pool_ is set
};

}  // namespace springy

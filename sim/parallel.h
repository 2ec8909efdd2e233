// springy: splitting a step over threads with results bit-identical to one thread.
//
// Floating-point addition is not associative, so the order in which a vertex's force terms are
// added decides the last bits of the result. springy fixes that order once for all thread
// counts: every vertex sums its terms stage by stage, and within a stage in element index
// order, exactly as the one-threaded loop does. Threads get it by owning vertices, not
// elements (the "owner computes" rule):
//   - the vertices are split into one contiguous index range per thread; addBody numbers each
//     body's vertices in slabs along its longest side, so a range is a compact region, the
//     vertices its elements reach in the next range are a short run of indices, and each
//     thread writes its own stretch of memory;
//   - each thread walks, in index order, the elements that touch a vertex it owns, and adds an
//     element's force only to the vertices it owns (ElementRef::mask); an element across a range
//     boundary is evaluated by each thread that owns one of its vertices (a few percent of
//     the work, measured in docs/benchmarks.md); the gas instead has each vertex gather its
//     faces' area vectors in face order (sim/forces.h);
//   - no two threads ever write the same vertex, so there are no atomics and no locks, and each
//     vertex sees the same terms in the same order as with one thread.
// Per-vertex loops (integrator updates, collisions) are split into contiguous index ranges;
// they are independent per vertex and need no ordering at all.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

namespace springy {

// One element (strut, hinge or face) in a thread's work list: its index, and which of its
// vertices the thread owns (bit i for the element's i-th vertex).
struct ElementRef {
  uint32_t index;
  uint32_t mask;
};

// The elements a force kernel evaluates, its one argument for "which": either all of a range
// [begin, end), adding to every vertex of each (one thread), or a thread's list of references,
// adding only to the vertices each reference's mask names. A kernel walks them with indexOf(r)
// and maskOf(r) for r in [0, count()) (Elements::visit), so one loop serves both.
class Elements {
 public:
  static Elements range(std::size_t begin, std::size_t end) { return Elements(nullptr, begin, end); }
  static Elements owned(const ElementRef* list, std::size_t count) { return Elements(list, 0, count); }
  static Elements owned(const std::vector<ElementRef>& list) { return owned(list.data(), list.size()); }
  std::size_t count() const { return end_ - begin_; }
  // The list of a thread's share, or null for a range starting at first().
  const ElementRef* list() const { return list_; }
  std::size_t first() const { return begin_; }

  // Calls body(count, indexOf, maskOf) with the index and mask functions of this selection
  // (function objects the compiler inlines into the kernel's loop, one copy per kind).
  template <class Body>
  void visit(Body&& body) const {
    if (list_ != nullptr)
      body(count(), ListIndex{list_}, ListMask{list_});
    else
      body(count(), RangeIndex{begin_}, AllVertices{});
  }

  struct RangeIndex {
    std::size_t begin;
    std::size_t operator()(std::size_t r) const { return begin + r; }
  };
  struct AllVertices {
    uint32_t operator()(std::size_t) const { return ~0u; }
  };
  struct ListIndex {
    const ElementRef* list;
    std::size_t operator()(std::size_t r) const { return list[r].index; }
  };
  struct ListMask {
    const ElementRef* list;
    uint32_t operator()(std::size_t r) const { return list[r].mask; }
  };

 private:
  // 16 bytes, so that a selection is passed in two registers (24 bytes went through memory and
  // measured 9-12% slower on BM_StrutKernel/4). Element counts fit 32 bits (sim/limits.h).
  Elements(const ElementRef* list, std::size_t begin, std::size_t end)
      : list_(list), begin_(static_cast<uint32_t>(begin)), end_(static_cast<uint32_t>(end)) {}
  const ElementRef* list_;
  uint32_t begin_, end_;
};

// The score a ThreadPool keeps of its workers (below): fed each job's own time and waiting time
// [ns]; at the end of each window of kWindow jobs it says how many of the next jobs to run alone
// (0: keep the workers). Separate, so that its rule is tested on its own.
class ContentionScore {
 public:
  static constexpr unsigned kWindow = 32;           // jobs per scored window
  static constexpr unsigned kMaxSoloWindows = 512;  // the longest run alone, in windows

  explicit ContentionScore(unsigned threads) : threads_(threads) {}
  uint64_t record(int64_t ownNs, int64_t waitNs);

 private:
  unsigned threads_;
  int64_t own_ = 0, wait_ = 0;
  unsigned jobs_ = 0;
  unsigned soloWindows_ = 1;
};

// A fixed set of worker threads that run one function on every share and wait for all of them
// (fork-join). The calling thread runs share 0 and takes part; workers spin briefly between jobs
// (a step issues several in a row) and then sleep on a futex.
//
// Shares are claimed, not assigned: a worker that wakes takes the next unclaimed share, and the
// calling thread, done with share 0, takes every share still unclaimed and runs it itself. So a
// worker that the OS has not scheduled (another process on its core, or the renderer's own
// threads) costs the step nothing but the claim: the caller never waits for a share that has not
// begun, only for one a worker is running. Results do not depend on who runs a share: share t
// reads and writes what fn(t) names, whichever thread calls it.
//
// A worker that claimed a share and was then preempted still holds the job up. So the pool keeps
// score: over a window of jobs, the time the caller waited for workers against the time its own
// shares took. When waiting cost more than running the other shares itself would have (wait >
// (threads - 1) x own time), the caller runs every share alone for the next windows, twice as
// many each time that a trial window loses again (up to 512 windows), and then tries the
// workers again. So a busy machine costs at most a trial window now and then, and an idle one
// keeps its threads.
class ThreadPool {
 public:
  explicit ThreadPool(unsigned threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  unsigned size() const { return threads_; }

  // Runs fn(t) for every share t in [0, size()), t = 0 on the calling thread, each exactly once,
  // on any thread; returns when all are done. fn must not throw.
  template <class F>
  void run(F&& fn) {
    if (threads_ == 1) {
      fn(0u);
      return;
    }
    dispatch([](void* ctx, unsigned t) { (*static_cast<F*>(ctx))(t); }, &fn);
  }

  // Splits [0, n) into size() contiguous ranges and runs fn(begin, end) for each.
  template <class F>
  void forRange(std::size_t n, F&& fn) {
    run([&](unsigned t) { fn(n * t / threads_, n * (t + 1) / threads_); });
  }

  // Shares the calling thread took over from workers since the pool was made (a measure of
  // contention: workers that did not start in time).
  uint64_t sharesTakenOver() const { return takenOver_.load(std::memory_order_relaxed); }
  // Jobs the caller ran alone because the workers had been losing time (see above).
  uint64_t soloJobs() const { return soloJobs_; }

 private:
  using Job = void (*)(void*, unsigned);
  void dispatch(Job job, void* ctx);
  void worker();
  // Claims the next share of the job in `state` (generation << 32 | next share) and runs it;
  // false if none is left. `state` is updated to the latest value seen.
  bool runNextShare(uint64_t& state);

  unsigned threads_;
  std::vector<std::thread> workers_;
  Job job_ = nullptr;
  void* ctx_ = nullptr;
  std::atomic<uint64_t> state_{0};    // generation << 32 | next unclaimed share
  std::atomic<uint32_t> pending_{0};  // shares 1.. not yet finished
  std::atomic<uint64_t> takenOver_{0};
  std::atomic<bool> stop_{false};
  // The calling thread's alone: the score, and the jobs left to run alone.
  ContentionScore score_;
  uint64_t soloLeft_ = 0, soloJobs_ = 0;
};

// Threads to use when the user gives none: SPRINGY_THREADS if set, else the hardware's count.
unsigned defaultThreadCount();

// The CPU time the calling thread has used [s] (CLOCK_THREAD_CPUTIME_ID). The cost of work done on
// one thread, which other work running beside it on other cores does not inflate as it inflates
// wall time (the studies time their runs with it while they run side by side).
double threadCpuSeconds();

}  // namespace springy

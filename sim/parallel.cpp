#include "sim/parallel.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdlib>
#include <ctime>
#include <string>
#include <string_view>

#include "sim/error.h"

namespace springy {
namespace {

// Spin this many times before sleeping: a step issues its jobs microseconds apart, so workers
// usually catch the next one spinning; between frames they sleep.
constexpr int kSpinLimit = 2000;

inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}

// Waits until `value` differs from `old`: spins, then sleeps on the atomic (a futex).
template <class T>
T waitWhileEqual(const std::atomic<T>& value, T old) {
  T now;
  int spins = 0;
  while ((now = value.load(std::memory_order_acquire)) == old) {
    if (++spins < kSpinLimit) cpuRelax();
    else value.wait(old, std::memory_order_acquire);
  }
  return now;
}

}  // namespace

uint64_t ContentionScore::record(int64_t ownNs, int64_t waitNs) {
  own_ += ownNs;
  wait_ += waitNs;
  if (++jobs_ < kWindow) return 0;
  // Waiting cost more than running the other threads' shares here would have.
  const bool losing = wait_ > static_cast<int64_t>(threads_ - 1) * own_;
  own_ = wait_ = 0;
  jobs_ = 0;
  if (!losing) {
    soloWindows_ = 1;
    return 0;
  }
  const uint64_t solo = static_cast<uint64_t>(soloWindows_) * kWindow;
  soloWindows_ = std::min(2 * soloWindows_, kMaxSoloWindows);
  return solo;
}

ThreadPool::ThreadPool(unsigned threads) : threads_(threads == 0 ? 1 : threads), score_(threads_) {
  // Generation 0 has no share left to claim.
  state_.store(threads_, std::memory_order_relaxed);
  workers_.reserve(threads_ - 1);
  for (unsigned t = 1; t < threads_; ++t) workers_.emplace_back([this] { worker(); });
}

ThreadPool::~ThreadPool() {
  stop_.store(true, std::memory_order_relaxed);
  // A new generation with no share to claim wakes every worker, which then sees stop_.
  const uint64_t generation = (state_.load(std::memory_order_relaxed) >> 32) + 1;
  state_.store(generation << 32 | threads_, std::memory_order_release);
  state_.notify_all();
  for (std::thread& w : workers_) w.join();
}

bool ThreadPool::runNextShare(uint64_t& state) {
  // A claim succeeds only on the current generation's state, so the job_ and ctx_ it reads
  // (published before that generation, acquired by the exchange) are that generation's, and the
  // dispatch cannot return, nor the next one begin, before the share is finished (pending_).
  while (static_cast<uint32_t>(state) < threads_) {
    if (state_.compare_exchange_weak(state, state + 1, std::memory_order_acq_rel, std::memory_order_acquire)) {
      job_(ctx_, static_cast<uint32_t>(state));
      if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) pending_.notify_one();
      state = state_.load(std::memory_order_acquire);
      return true;
    }
  }
  return false;
}

void ThreadPool::dispatch(Job job, void* ctx) {
  if (soloLeft_ > 0) {
    --soloLeft_;
    ++soloJobs_;
    for (unsigned t = 0; t < threads_; ++t) job(ctx, t);
    return;
  }
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  job_ = job;
  ctx_ = ctx;
  pending_.store(threads_ - 1, std::memory_order_relaxed);
  const uint64_t generation = (state_.load(std::memory_order_relaxed) >> 32) + 1;
  state_.store(generation << 32 | 1u, std::memory_order_release);  // publishes job_ and ctx_
  state_.notify_all();
  job(ctx, 0);
  const Clock::time_point own = Clock::now();
  // Every share no worker has claimed yet, here.
  uint64_t state = state_.load(std::memory_order_acquire);
  while (runNextShare(state)) takenOver_.fetch_add(1, std::memory_order_relaxed);
  const Clock::time_point claimed = Clock::now();
  uint32_t left = pending_.load(std::memory_order_acquire);
  while (left != 0) left = waitWhileEqual(pending_, left);
  const Clock::time_point end = Clock::now();
  // The score: the shares taken over count as the caller's own work, not as waiting.
  soloLeft_ = score_.record(std::chrono::duration_cast<std::chrono::nanoseconds>(own - start).count(),
                            std::chrono::duration_cast<std::chrono::nanoseconds>(end - claimed).count());
}

void ThreadPool::worker() {
  uint64_t state = state_.load(std::memory_order_acquire);
  for (;;) {
    // (`state` always comes from an acquiring load: if it is the last generation, stop_ shows.)
    if (stop_.load(std::memory_order_relaxed)) return;
    // Nothing to claim in this state: wait for the next generation.
    if (static_cast<uint32_t>(state) >= threads_) state = waitWhileEqual(state_, state);
    if (stop_.load(std::memory_order_relaxed)) return;
    while (runNextShare(state)) {
    }
  }
}

unsigned defaultThreadCount() {
  if (const char* env = std::getenv("SPRINGY_THREADS"); env != nullptr && *env != '\0') {
    const std::string_view text(env);
    unsigned value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size() || value == 0 || value > 256) {
      throw Error("SPRINGY_THREADS=" + std::string(text) + ": expected a thread count from 1 to 256");
    }
    return value;
  }
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware == 0 ? 1 : hardware;
}

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace springy

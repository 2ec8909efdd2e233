#include "sim/parallel.h"

#include <charconv>
#include <cstdlib>
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

ThreadPool::ThreadPool(unsigned threads) : threads_(threads == 0 ? 1 : threads) {
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
  job_ = job;
  ctx_ = ctx;
  pending_.store(threads_ - 1, std::memory_order_relaxed);
  const uint64_t generation = (state_.load(std::memory_order_relaxed) >> 32) + 1;
  state_.store(generation << 32 | 1u, std::memory_order_release);  // publishes job_ and ctx_
  state_.notify_all();
  job(ctx, 0);
  // Every share no worker has claimed yet, here.
  uint64_t state = state_.load(std::memory_order_acquire);
  while (runNextShare(state)) takenOver_.fetch_add(1, std::memory_order_relaxed);
  uint32_t left = pending_.load(std::memory_order_acquire);
  while (left != 0) left = waitWhileEqual(pending_, left);
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

}  // namespace springy

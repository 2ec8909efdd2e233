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
  workers_.reserve(threads_ - 1);
  for (unsigned t = 1; t < threads_; ++t) workers_.emplace_back([this, t] { worker(t); });
}

ThreadPool::~ThreadPool() {
  stop_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (std::thread& w : workers_) w.join();
}

void ThreadPool::dispatch(Job job, void* ctx) {
  job_ = job;
  ctx_ = ctx;
  pending_.store(threads_ - 1, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);  // publishes job_ and ctx_
  generation_.notify_all();
  job(ctx, 0);
  uint32_t left = pending_.load(std::memory_order_acquire);
  while (left != 0) left = waitWhileEqual(pending_, left);
}

void ThreadPool::worker(unsigned index) {
  uint32_t seen = 0;
  for (;;) {
    seen = waitWhileEqual(generation_, seen);
    if (stop_.load(std::memory_order_relaxed)) return;
    job_(ctx_, index);
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) pending_.notify_one();
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

#include "sim/interrupt.h"

#include <atomic>

namespace springy {
namespace {

// Written by a signal handler, read by every thread.
std::atomic<int> gSignal{0};
static_assert(std::atomic<int>::is_always_lock_free);

}  // namespace

bool interrupted() { return gSignal.load() != 0; }

void requestInterrupt(int signal) {
  int none = 0;
  gSignal.compare_exchange_strong(none, signal);  // the first request decides the exit status
}

void clearInterrupt() { gSignal.store(0); }
int interruptSignal() { return gSignal.load(); }

}  // namespace springy

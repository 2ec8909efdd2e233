#include "app/progress.h"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace springy {

Progress::Progress(std::string label, long total, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), terminal_(::isatty(STDERR_FILENO) != 0),
      interval_(terminal_ ? 1.0 : 5.0), start_(Clock::now()), lastPrint_(start_), lastCount_(start_),
      ticker_([this] { tick(); }) {}

Progress::~Progress() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopped_ = true;
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
}

void Progress::tick() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopped_) {
    wake_.wait_for(lock, std::chrono::duration<double>(interval_ / 4));
    const auto now = Clock::now();
    // The first line sooner: a log shows within 2 s that the work has begun.
    const double due = lastPrint_ == start_ ? std::min(interval_, 2.0) : interval_;
    if (!stopped_ && std::chrono::duration<double>(now - lastPrint_).count() >= due) print(now);
  }
}

void Progress::update(long done, const std::string& detail) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (stopped_) return;
  const auto now = Clock::now();
  if (done != done_) lastCount_ = now;
  done_ = done;
  detail_ = detail;
  const double sinceLast = std::chrono::duration<double>(now - lastPrint_).count();
  if (sinceLast < (terminal_ ? 0.2 : 5.0) && done < total_) return;
  print(now);
}

void Progress::print(Clock::time_point now) {
  lastPrint_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fraction = total_ > 0 ? static_cast<double>(done_) / static_cast<double>(total_) : 1.0;
  // The ETA once something was counted; before, the time so far. A count that takes long says so.
  char times[96];
  if (done_ > 0) {
    std::snprintf(times, sizeof times, "ETA %.0f s", elapsed * static_cast<double>(total_ - done_) / static_cast<double>(done_));
  } else {
    std::snprintf(times, sizeof times, "%.0f s so far", elapsed);
  }
  const double onThis = std::chrono::duration<double>(now - lastCount_).count();
  std::string detail = detail_;
  if (done_ > 0 && done_ < total_ && onThis >= interval_) {
    char working[96];
    std::snprintf(working, sizeof working, "%s%.0f s on the next", detail.empty() ? "" : ", ", onThis);
    detail += working;
  }
  if (terminal_) {
    constexpr int width = 24;
    char bar[width + 1];
    const int filled = static_cast<int>(fraction * width);
    for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
    bar[width] = 0;
    std::fprintf(stderr, "\r%s [%s] %ld/%ld %s, %s%s%s   ", label_.c_str(), bar, done_, total_, unit_.c_str(), times,
                 detail.empty() ? "" : ", ", detail.c_str());
  } else {
    std::fprintf(stderr, "%s: %ld/%ld %s (%.0f%%), %s%s%s\n", label_.c_str(), done_, total_, unit_.c_str(),
                 100.0 * fraction, times, detail.empty() ? "" : ", ", detail.c_str());
  }
  std::fflush(stderr);
}

void Progress::finish() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (stopped_) return;
  stopped_ = true;
  wake_.notify_all();
  if (terminal_) std::fprintf(stderr, "\n");
}

}  // namespace springy

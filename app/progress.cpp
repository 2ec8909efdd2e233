#include "app/progress.h"

#include <cstdio>
#include <unistd.h>

namespace springy {

Progress::Progress(std::string label, long total, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), terminal_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()), lastPrint_(start_) {}

void Progress::update(long done, const std::string& detail) {
  const auto now = std::chrono::steady_clock::now();
  const double sinceLast = std::chrono::duration<double>(now - lastPrint_).count();
  if (sinceLast < (terminal_ ? 0.2 : 5.0) && done < total_) return;
  lastPrint_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double eta = done > 0 ? elapsed * static_cast<double>(total_ - done) / static_cast<double>(done) : 0.0;
  const double fraction = total_ > 0 ? static_cast<double>(done) / static_cast<double>(total_) : 1.0;
  if (terminal_) {
    constexpr int width = 24;
    char bar[width + 1];
    const int filled = static_cast<int>(fraction * width);
    for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
    bar[width] = 0;
    std::fprintf(stderr, "\r%s [%s] %ld/%ld %s, ETA %.0f s, %s   ", label_.c_str(), bar, done, total_, unit_.c_str(), eta,
                 detail.c_str());
  } else {
    std::fprintf(stderr, "%s: %ld/%ld %s (%.0f%%), ETA %.0f s, %s\n", label_.c_str(), done, total_, unit_.c_str(),
                 100.0 * fraction, eta, detail.c_str());
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (terminal_) std::fprintf(stderr, "\n");
}

}  // namespace springy

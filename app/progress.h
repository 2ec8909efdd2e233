// springy app: progress on stderr. A live bar when stderr is a terminal, a plain line every
// few seconds otherwise (logs, CI).
//
// Time-based as well as count-based: a thread of its own prints the line again when nothing was
// counted for a while (every second on a terminal, every 5 s in a log, the first time after
// 2 s), with the time spent on the count in hand, so that a frame that takes minutes (vbd at 1000
// sweeps a step, a tiny step) still shows within seconds that springy is working.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace springy {

class Progress {
 public:
  // `unit`: what is counted ("frames", "runs").
  Progress(std::string label, long total, std::string unit = "frames");
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  // `detail`: per-stage figures to show after the counts. Any thread.
  void update(long done, const std::string& detail);
  // Ends the line (a terminal's bar) and the reprinting.
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  void print(Clock::time_point now);  // with mutex_ held
  void tick();                        // the reprinting thread

  std::string label_, unit_;
  long total_;
  bool terminal_;
  double interval_;  // [s] between lines at most
  std::mutex mutex_;  // guards what follows and the printing
  std::condition_variable wake_;
  bool stopped_ = false;
  long done_ = 0;
  std::string detail_;
  Clock::time_point start_, lastPrint_, lastCount_;
  std::thread ticker_;  // last: started once the rest is set
};

}  // namespace springy

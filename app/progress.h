// springy app: progress on stderr. A live bar when stderr is a terminal, a plain line every
// few seconds otherwise (logs, CI).
#pragma once

#include <chrono>
#include <string>

namespace springy {

class Progress {
 public:
  // `unit`: what is counted ("frames", "runs").
  Progress(std::string label, long total, std::string unit = "frames");
  // `detail`: per-stage figures to show after the counts.
  void update(long done, const std::string& detail);
  void finish();

 private:
  std::string label_, unit_;
  long total_;
  bool terminal_;
  std::chrono::steady_clock::time_point start_, lastPrint_;
};

}  // namespace springy

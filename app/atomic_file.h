// springy: output files that appear complete or not at all.
//
// Output is written to a temporary file beside the target (same directory, so the final
// rename is atomic on POSIX) and renamed over the target only by commit(). If the program
// fails or is interrupted first, the destructor removes the temporary file: a failure never
// leaves a truncated file under the final name and never destroys an existing one.
#pragma once

#include <string>

namespace springy {

class AtomicFile {
 public:
  // Creates the temporary file at once, so an unwritable target is reported before any work.
  // Throws springy::Error naming the target.
  explicit AtomicFile(std::string target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& temporaryPath() const { return temporary_; }
  const std::string& target() const { return target_; }
  // Renames the temporary file over the target. Throws springy::Error on failure.
  void commit();

 private:
  std::string target_, temporary_;
  bool committed_ = false;
};

// Set by SIGINT / SIGTERM; long loops poll it and stop, so temporary files are cleaned up.
bool interrupted();
void installInterruptHandler();

}  // namespace springy

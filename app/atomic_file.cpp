#include "app/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sim/error.h"

namespace springy {
namespace {
volatile std::sig_atomic_t gInterrupted = 0;
void onSignal(int) { gInterrupted = 1; }
}  // namespace

bool interrupted() { return gInterrupted != 0; }

void installInterruptHandler() {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

AtomicFile::AtomicFile(std::string target) : target_(std::move(target)) {
  namespace fs = std::filesystem;
  const fs::path path(target_);
  if (fs::is_directory(path)) throw Error(target_ + ": is a directory, expected a file name");
  // Keep the extension last (tools such as FFmpeg pick the container from it).
  std::string pattern = (path.parent_path() / ("." + path.stem().string() + ".tmp-XXXXXX")).string();
  const std::string extension = path.extension().string();
  pattern += extension;
  std::string buffer = pattern;
  const int fd = mkstemps(buffer.data(), static_cast<int>(extension.size()));
  if (fd < 0) throw Error(target_ + ": cannot write here: " + std::strerror(errno));
  // mkstemps creates the file private (0600); give it the permissions a new file would get.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  ::close(fd);
  temporary_ = buffer;
}

AtomicFile::~AtomicFile() {
  if (!committed_) std::remove(temporary_.c_str());
}

void AtomicFile::commit() {
  if (std::rename(temporary_.c_str(), target_.c_str()) != 0) {
    throw Error(target_ + ": cannot rename the finished output into place: " + std::strerror(errno));
  }
  committed_ = true;
}

}  // namespace springy

// springy app: a spill file (see SpillFile).
#pragma once

#include <fcntl.h>
#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <string>
#include <vector>

#include "app/atomic_file.h"
#include "sim/error.h"

namespace springy {

// An anonymous file beside an output, for data written before what must precede it is known (a
// GLB's binary chunk, a report's replay): unlinked at once, so the system removes it when it is
// closed, whatever happens.
class SpillFile {
 public:
  SpillFile(const std::string& target) : target_(target) {
    const std::size_t slash = target.rfind('/');
    std::string name = (slash == std::string::npos ? std::string() : target.substr(0, slash + 1)) + ".springy-spill-XXXXXX";
    fd_ = ::mkostemp(name.data(), O_CLOEXEC);
    if (fd_ < 0) throw Error(target + ": cannot write here: " + errorText(errno));
    ::unlink(name.c_str());
  }
  ~SpillFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;

  // Appends; returns the offset the bytes start at.
  uint64_t write(const void* data, std::size_t size) {
    const uint64_t at = size_;
    const auto* p = static_cast<const uint8_t*>(data);
    while (size > 0) {
      const ssize_t n = ::write(fd_, p, size);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) fail(n < 0 ? errno : EIO);
      p += n, size -= static_cast<std::size_t>(n), size_ += static_cast<uint64_t>(n);
    }
    return at;
  }
  template <typename T>
  uint64_t write(const std::vector<T>& values) {
    return write(values.data(), values.size() * sizeof(T));
  }
  uint64_t size() const { return size_; }
  // Passes everything written to `sink(const uint8_t*, size_t)` in order, in chunks of a multiple
  // of 3 bytes but the last (so a sink can encode them as base64 one by one).
  template <typename Sink>
  void read(Sink&& sink) {
    std::vector<uint8_t> chunk(3 << 18);
    for (uint64_t at = 0; at < size_;) {
      const std::size_t want = static_cast<std::size_t>(std::min<uint64_t>(chunk.size(), size_ - at));
      const ssize_t n = ::pread(fd_, chunk.data(), want, static_cast<off_t>(at));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) fail(n < 0 ? errno : EIO);
      if (static_cast<std::size_t>(n) < want) {  // a short read: read the rest before passing it on
        std::size_t got = static_cast<std::size_t>(n);
        while (got < want) {
          const ssize_t m = ::pread(fd_, chunk.data() + got, want - got, static_cast<off_t>(at + got));
          if (m < 0 && errno == EINTR) continue;
          if (m <= 0) fail(m < 0 ? errno : EIO);
          got += static_cast<std::size_t>(m);
        }
      }
      sink(chunk.data(), want);
      at += want;
    }
  }
  // Copies everything written into `out`.
  void copyTo(AtomicFile& out) {
    read([&out](const uint8_t* data, std::size_t size) { out.write({data, size}); });
  }

 private:
  [[noreturn]] void fail(int error) {
    throw Error(target_ + ": writing failed: " + errorText(error) + " (" + target_ + " left as it was)");
  }
  std::string target_;
  int fd_ = -1;
  uint64_t size_ = 0;
};

}  // namespace springy

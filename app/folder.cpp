#include "app/folder.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "app/atomic_file.h"
#include "sim/error.h"

namespace springy {

void removeTree(const std::string& path) {
  std::error_code ignored;
  std::filesystem::remove_all(path, ignored);
}

OutputFolder::OutputFolder(std::string target, std::string marker, const std::string& markerText,
                           const std::string& what)
    : target_(std::move(target)), marker_(std::move(marker)), what_(what) {
  while (target_.size() > 1 && target_.back() == '/') target_.pop_back();
  struct stat st {};
  if (::lstat(target_.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw Error(what_ + ": " + target_ + " exists and is not a folder");
    if (::access((target_ + "/" + marker_).c_str(), F_OK) != 0) {
      std::error_code ec;
      if (!std::filesystem::is_empty(target_, ec) || ec) {
        throw Error(what_ + ": " + target_ +
                    " exists, is not empty and was not written by springy (it holds no " + marker_ +
                    "); pick another folder or empty it");
      }
    }
  }
  const std::filesystem::path t(target_);
  const std::filesystem::path parent = t.has_parent_path() ? t.parent_path() : std::filesystem::path(".");
  std::string temporary = (parent / ("." + t.filename().string() + ".tmp-XXXXXX")).string();
  if (!::mkdtemp(temporary.data())) {
    throw Error(what_ + ": cannot create a folder in " + parent.string() + ": " + errorText(errno));
  }
  temporary_ = temporary;
  try {
    writeFileAtomically(temporary_ + "/" + marker_, markerText);
  } catch (...) {
    removeTree(temporary_);
    throw;
  }
}

OutputFolder::~OutputFolder() {
  if (!temporary_.empty()) removeTree(temporary_);
}

void OutputFolder::fail(const std::string& what, int error) const {
  throw Error(what_ + ": " + target_ + ": " + what + ": " + errorText(error) + " (" + target_ + " left as it was)");
}

void OutputFolder::commit() {
  // What was written reaches the disk before the folder gets its name.
  const int dir = ::open(temporary_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0 || ::syncfs(dir) != 0) fail("writing failed", errno);
  ::close(dir);
  std::string old;
  struct stat st {};
  if (::lstat(target_.c_str(), &st) == 0) {
    old = temporary_ + ".old";
    if (std::rename(target_.c_str(), old.c_str()) != 0) fail("cannot move the earlier folder aside", errno);
  }
  if (std::rename(temporary_.c_str(), target_.c_str()) != 0) {
    const int error = errno;
    if (!old.empty()) std::rename(old.c_str(), target_.c_str());
    fail("cannot rename the finished folder into place", error);
  }
  temporary_.clear();
  if (!old.empty()) removeTree(old);
}

}  // namespace springy

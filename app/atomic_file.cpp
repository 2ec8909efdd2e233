#include "app/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
#include <sstream>
#include <vector>

#include "sim/error.h"

namespace springy {
namespace {

void onSignal(int signal) { requestInterrupt(signal); }  // the first signal decides the exit status

// The temporaries that exist now, for a signal handler to remove: a fixed table (a handler may
// not allocate), each slot written whole before it is marked live. `owner` keeps a forked child
// (the mesh reader's, which ends by SIGALRM on a hang) from removing its parent's files.
struct TemporarySlot {
  std::atomic<int> state{0};  // 0 free, 1 being filled, 2 live
  pid_t owner = 0;
  bool folder = false;
  char path[PATH_MAX] = {};
};
TemporarySlot temporaries[64];

// Removes `name` under the directory `parent` and, for a folder, everything in it, with system
// calls only (async-signal-safe: for a signal handler). True when it is gone.
bool removeNow(int parent, const char* name, int depth) {
  if (::unlinkat(parent, name, 0) == 0 || errno == ENOENT) return true;
  if ((errno != EISDIR && errno != EPERM) || depth > 32) return false;
  const int fd = ::openat(parent, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return false;
  alignas(8) char entries[4096];
  for (bool removed = true; removed;) {  // from the start again after each batch: removal moves entries
    removed = false;
    ::lseek(fd, 0, SEEK_SET);
    const long n = ::syscall(SYS_getdents64, fd, entries, sizeof entries);
    // struct linux_dirent64: inode (8 bytes), offset (8), record length (2), type (1), name.
    for (long at = 0; at < n;) {
      unsigned short length = 0;
      std::memcpy(&length, entries + at + 16, sizeof length);
      const char* entry = entries + at + 19;
      at += length;
      if (std::strcmp(entry, ".") == 0 || std::strcmp(entry, "..") == 0) continue;
      // Only what went counts: an entry that cannot be removed would be read again for ever.
      removed = removeNow(fd, entry, depth + 1) || removed;
    }
  }
  ::close(fd);
  return ::unlinkat(parent, name, AT_REMOVEDIR) == 0;
}

// The signals that end the process at once, and what they did before springy's handler.
constexpr int kFatalSignals[] = {SIGQUIT, SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGSYS, SIGALRM, SIGUSR1,
                                 SIGUSR2, SIGVTALRM, SIGPROF, SIGXCPU, SIGPWR};
struct sigaction previousActions[NSIG];

void onFatalSignal(int signal, siginfo_t* info, void*) {
  const pid_t self = ::getpid();
  for (TemporarySlot& slot : temporaries) {
    if (slot.state.load(std::memory_order_acquire) != 2 || slot.owner != self) continue;
    if (slot.folder) {
      removeNow(AT_FDCWD, slot.path, 0);
    } else {
      ::unlink(slot.path);
    }
  }
  // Then what the signal did before (the default: end, with a core dump for a crash; or a
  // sanitizer's report). A fault the kernel raised happens again when the handler returns.
  ::sigaction(signal, &previousActions[signal], nullptr);
  const bool fault = signal == SIGSEGV || signal == SIGBUS || signal == SIGFPE || signal == SIGILL;
  if (!(fault && info && info->si_code > 0)) ::raise(signal);
}

// The directory part of `path` with its trailing '/', or "" for a bare name.
std::string directoryOf(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

std::string baseNameOf(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// `path` with its symbolic links followed to the file they end at, which may not exist yet (a new
// output, or the end of a dangling link). Links in the directory part are left to the kernel.
std::string followLinks(const std::string& path) {
  std::string p = path;
  for (int hops = 0;; ++hops) {
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0) {
      if (errno == ENOENT) return p;
      throw Error(path + ": cannot write here: " + errorText(errno));
    }
    if (!S_ISLNK(st.st_mode)) return p;
    // The kernel's own limit (40 on Linux) before it reports a loop.
    if (hops == 40) throw Error(path + ": cannot write here: " + errorText(ELOOP));
    std::string link(static_cast<std::size_t>(st.st_size > 0 ? st.st_size : 4096) + 1, '\0');
    const ssize_t n = ::readlink(p.c_str(), link.data(), link.size());
    if (n <= 0) {
      throw Error(path + ": cannot read the symbolic link '" + p + "': " + errorText(n < 0 ? errno : ENOENT));
    }
    link.resize(static_cast<std::size_t>(n));
    p = link.front() == '/' ? link : directoryOf(p) + link;
  }
}

}  // namespace

std::string errorText(int error) { return std::strerror(error); }

int interruptedExitStatus() {
  const int s = interruptSignal();
  return 128 + (s != 0 ? s : SIGINT);
}

int registerTemporary(const std::string& path, bool folder) {
  if (path.size() >= PATH_MAX) return -1;
  for (int k = 0; k < static_cast<int>(std::size(temporaries)); ++k) {
    TemporarySlot& slot = temporaries[k];
    int expected = 0;
    if (!slot.state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(slot.path, path.c_str(), path.size() + 1);
    slot.owner = ::getpid();
    slot.folder = folder;
    slot.state.store(2, std::memory_order_release);
    return k;
  }
  return -1;
}

void forgetTemporary(int handle) {
  if (handle >= 0) temporaries[handle].state.store(0, std::memory_order_release);
}

void installInterruptHandler() {
  struct sigaction action {};
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  // Restart interrupted system calls: the loops poll the flag, no call needs to see EINTR.
  action.sa_flags = SA_RESTART;
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    // A signal ignored by the parent stays ignored: `nohup springy render ...` must survive logout.
    if (::sigaction(signal, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    ::sigaction(signal, &action, nullptr);
  }
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  ::sigaction(SIGPIPE, &ignore, nullptr);
  ::sigaction(SIGXFSZ, &ignore, nullptr);
  struct sigaction fatal {};
  fatal.sa_sigaction = onFatalSignal;
  fatal.sa_flags = SA_SIGINFO;
  sigemptyset(&fatal.sa_mask);
  for (const int signal : kFatalSignals) {
    if (::sigaction(signal, nullptr, &previousActions[signal]) != 0) continue;
    // Ignored by the parent stays so. A fault is chained to the handler before (a sanitizer's
    // report); any other signal is taken only over the default action (which ends the process),
    // so that a handler someone else set (a profiler's SIGPROF) keeps its signal not fatal.
    const bool fault = signal == SIGSEGV || signal == SIGBUS || signal == SIGFPE || signal == SIGILL;
    if (previousActions[signal].sa_handler == SIG_IGN) continue;
    if (!fault && previousActions[signal].sa_handler != SIG_DFL) continue;
    ::sigaction(signal, &fatal, nullptr);
  }
}

std::uint64_t contentHash(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  std::vector<unsigned char> buffer(1 << 20);
  std::uint64_t h = 14695981039346656037ULL;
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    std::size_t k = 0;
    for (; k + 8 <= static_cast<std::size_t>(n); k += 8) {
      std::uint64_t word = 0;
      std::memcpy(&word, buffer.data() + k, 8);
      h = (h ^ word) * 1099511628211ULL;
    }
    for (; k < static_cast<std::size_t>(n); ++k) h = (h ^ buffer[k]) * 1099511628211ULL;
  }
  ::close(fd);
  return h;
}

std::string escapedPath(const std::string& path) {
  std::string out;
  for (const char c : path) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte > ' ' && c != '%') {
      out += c;
      continue;
    }
    char hex[4];
    std::snprintf(hex, sizeof hex, "%%%02X", byte);
    out += hex;
  }
  return out;
}

std::string unescapedPath(const std::string& word) {
  std::string out;
  for (std::size_t i = 0; i < word.size(); ++i) {
    if (word[i] == '%' && i + 2 < word.size() && std::isxdigit(static_cast<unsigned char>(word[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(word[i + 2]))) {
      out += static_cast<char>(std::stoi(word.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += word[i];
    }
  }
  return out;
}

namespace {

constexpr const char* kOwnedRecord = ".springy-files";
constexpr const char* kOwnedHeader =
    "# The files springy wrote in this folder, by name: size, a hash of the bytes, the name. springy\n"
    "# replaces only these (as they were); any other file of a name it writes here stops it.\n";

// The record of `folder`: name -> (size, hash).
std::map<std::string, std::pair<std::uintmax_t, std::uint64_t>> readOwned(const std::string& folder) {
  std::map<std::string, std::pair<std::uintmax_t, std::uint64_t>> out;
  std::istringstream lines(firstBytes(folder + "/" + kOwnedRecord, std::size_t{16} << 20));
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::uintmax_t size = 0;
    std::uint64_t hash = 0;
    std::string name;
    if (words >> size >> hash >> name) out[unescapedPath(name)] = {size, hash};
  }
  return out;
}

std::string folderOf(const std::string& path) {
  const std::string dir = directoryOf(path);
  return dir.empty() ? std::string(".") : dir.substr(0, dir.size() - 1);
}

bool owned(const std::map<std::string, std::pair<std::uintmax_t, std::uint64_t>>& record, const std::string& path,
           const struct stat& st) {
  const auto it = record.find(baseNameOf(path));
  return it != record.end() && it->second.first == static_cast<std::uintmax_t>(st.st_size) &&
         it->second.second == contentHash(path);
}

}  // namespace

void refuseUnlessOwned(const std::string& path, const std::string& whose) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return;
  if (S_ISREG(st.st_mode) && owned(readOwned(folderOf(path)), path, st)) return;
  throw Error(path + ": exists and was not written by springy (or changed since: " + folderOf(path) + "/" +
              kOwnedRecord + " does not list it as it is); " + whose +
              ": refusing to replace it. Move it away, or name another output folder");
}

void refuseUnownedIn(const std::string& folder, const std::function<bool(const std::string&)>& writes,
                     const std::string& whose) {
  std::error_code error;
  std::vector<std::string> foreign;
  const auto record = readOwned(folder);
  for (std::filesystem::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (!writes(name)) continue;
    struct stat st {};
    const std::string path = it->path().string();
    if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || !owned(record, path, st)) foreign.push_back(name);
  }
  if (foreign.empty()) return;
  std::sort(foreign.begin(), foreign.end());
  std::string list;
  for (std::size_t k = 0; k < foreign.size() && k < 10; ++k) list += (k ? ", " : "") + foreign[k];
  if (foreign.size() > 10) list += " and " + std::to_string(foreign.size() - 10) + " more";
  throw Error(folder + ": holds files of the names " + whose + " that springy did not write (or that changed since: " +
              kOwnedRecord + " does not list them as they are): " + list +
              "; refusing to replace them. Move them away, or name another output folder");
}

void recordOwned(const std::string& path) {
  const std::string folder = folderOf(path);
  auto record = readOwned(folder);
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;
  record[baseNameOf(path)] = {static_cast<std::uintmax_t>(st.st_size), contentHash(path)};
  std::string text = kOwnedHeader;
  for (const auto& [name, entry] : record) {
    text += std::to_string(entry.first) + " " + std::to_string(entry.second) + " " + escapedPath(name) + "\n";
  }
  writeFileAtomically(folder + "/" + kOwnedRecord, text);
}

void writeOwnedFile(const std::string& path, std::string_view text, const std::string& whose) {
  refuseUnlessOwned(path, whose);
  writeFileAtomically(path, text);
  recordOwned(path);
}

void refuseInputs(const std::string& target, const std::vector<std::string>& inputs) {
  for (const std::string& input : inputs) {
    if (sameFile(target, input)) {
      throw Error(target + ": is the input file '" + input + "'; refusing to write over it");
    }
  }
}

std::string firstBytes(const std::string& path, std::size_t count) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return {};
  std::string bytes(count, '\0');
  std::size_t got = 0;
  while (got < count) {
    const ssize_t n = ::read(fd, bytes.data() + got, count - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  bytes.resize(got);
  return bytes;
}

void refuseUnlessMarked(const std::string& path, std::string_view mark, std::size_t within, const std::string& whose) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;
  if (S_ISREG(st.st_mode) && firstBytes(path, within).find(mark) != std::string::npos) return;
  throw Error(path + ": exists and was not written by springy (it does not carry \"" + std::string(mark) + "\"); " +
              whose + ": refusing to replace it. Move it away, or name another output");
}

bool isDirectory(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool sameFile(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

void makeDirectories(const std::string& path, const std::string& what) {
  auto fail = [&](const std::string& part, int error) {
    throw Error(what + " '" + path + "': cannot create the directory '" + part + "': " + errorText(error));
  };
  if (path.empty()) return;
  // Each prefix ending before a '/', then the whole path.
  for (std::size_t end = path.find('/', 1);; end = path.find('/', end + 1)) {
    const std::string part = path.substr(0, end);
    if (!part.empty() && part.back() != '/' && ::mkdir(part.c_str(), 0777) != 0) {
      const int error = errno;
      if (error != EEXIST) fail(part, error);
      struct stat st {};
      if (::stat(part.c_str(), &st) != 0) fail(part, errno);  // e.g. a dangling link, a loop
      if (!S_ISDIR(st.st_mode)) fail(part, ENOTDIR);
    }
    if (end == std::string::npos) return;
  }
}

AtomicFile::AtomicFile(std::string target, const std::vector<std::string>& inputs) : target_(std::move(target)) {
  if (target_.empty()) throw Error("an output file name is empty");
  if (target_.back() == '/' || isDirectory(target_)) throw Error(target_ + ": is a directory, expected a file name");
  refuseInputs(target_, inputs);
  resolved_ = followLinks(target_);
  mode_t mode = 0;
  struct stat st {};
  if (::stat(resolved_.c_str(), &st) == 0) {
    // Renaming over anything else (a device, a pipe) would replace it rather than write to it.
    if (!S_ISREG(st.st_mode)) {
      throw Error(target_ + ": is not a regular file (outputs are written beside it and renamed over it)");
    }
    mode = st.st_mode & 07777;  // a replaced file keeps its permissions
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    mode = 0666 & ~mask;  // what a newly created file would get
  }
  // ".NAME.tmp-XXXXXX.EXT": hidden, and the extension last (FFmpeg picks the container from it).
  // The stem is shortened when needed so that a name near the limit still has a temporary name.
  const std::string base = baseNameOf(resolved_);
  const std::size_t dot = base.rfind('.');
  std::string extension = dot != std::string::npos && dot > 0 && base.size() - dot <= 16 ? base.substr(dot) : "";
  std::string stem = base.substr(0, base.size() - extension.size());
  const std::string marker = ".tmp-XXXXXX";
  constexpr std::size_t kNameMax = 255;
  const std::size_t fixed = 1 + marker.size() + extension.size();
  if (fixed + stem.size() > kNameMax) stem.resize(kNameMax > fixed ? kNameMax - fixed : 0);
  std::string buffer = directoryOf(resolved_) + "." + stem + marker + extension;
  const int fd = ::mkostemps(buffer.data(), static_cast<int>(extension.size()), O_CLOEXEC);
  if (fd < 0) throw Error(target_ + ": cannot write here: " + errorText(errno));
  // mkostemps creates the file private (0600). (The destructor does not run for a constructor
  // that throws: clean up here.)
  if (::fchmod(fd, mode) != 0) {
    const int error = errno;
    ::close(fd);
    ::unlink(buffer.c_str());
    throw Error(target_ + ": cannot set the permissions of " + buffer + ": " + errorText(error));
  }
  fd_ = fd;
  temporary_ = buffer;
  registered_ = registerTemporary(temporary_, false);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temporary_.empty()) ::unlink(temporary_.c_str());
  forgetTemporary(registered_);
}

void AtomicFile::fail(const std::string& what, int error) {
  // Throwing here leaves the temporary file to the destructor.
  throw Error(target_ + ": " + what + ": " + errorText(error) + " (" + target_ + " left as it was)");
}

void AtomicFile::write(std::span<const std::uint8_t> bytes) {
  if (fd_ < 0) throw Error(target_ + ": written after it was committed");
  usedWrite_ = true;
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd_, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("writing failed", errno);
    }
    if (n == 0) fail("writing failed", EIO);
    bytes = bytes.subspan(static_cast<std::size_t>(n));
    written_ += static_cast<std::uint64_t>(n);
  }
}

void AtomicFile::commit() {
  if (fd_ < 0) throw Error(target_ + ": committed twice");
  // The data must be on disk before the rename makes it the target: otherwise a crash soon after
  // can leave an empty file under the final name. fsync also reports delayed write errors.
  if (::fsync(fd_) != 0) fail("writing failed", errno);
  struct stat st {};
  if (::fstat(fd_, &st) != 0) fail("cannot examine " + temporary_, errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("writing failed", errno);
  if (st.st_size == 0) throw Error(target_ + ": the output is empty; not written (" + target_ + " left as it was)");
  if (usedWrite_ && static_cast<std::uint64_t>(st.st_size) != written_) {
    throw Error(target_ + ": " + std::to_string(st.st_size) + " bytes on disk, " + std::to_string(written_) +
                " written; not written (" + target_ + " left as it was)");
  }
  if (std::rename(temporary_.c_str(), resolved_.c_str()) != 0) {
    fail("cannot rename the finished output into place", errno);
  }
  committed_ = true;
  forgetTemporary(registered_);
  registered_ = -1;
  // Make the rename itself durable. Best effort: some file systems cannot sync a directory, and
  // the output is complete either way.
  const std::string directory = directoryOf(resolved_);
  const int dirFd = ::open(directory.empty() ? "." : directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dirFd >= 0) {
    ::fsync(dirFd);
    ::close(dirFd);
  }
}

void writeFileAtomically(const std::string& path, std::string_view text, const std::vector<std::string>& inputs) {
  AtomicFile file(path, inputs);
  file.write(text);
  file.commit();
}

}  // namespace springy

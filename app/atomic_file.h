// springy: output files that appear complete or not at all, and the signals that stop a run.
//
// Every output (videos, stills, traces) goes through AtomicFile: it is written to a temporary
// file beside the target (same directory, so the final rename is atomic on POSIX) and renamed
// over the target only by commit(), after the data was verified (every write checked, fsync
// and close succeeded, the file is not empty). If the program fails or is interrupted first,
// the destructor removes the temporary file: a failure never leaves a truncated file under the
// final name and never destroys an existing one.
//
// Only non-throwing system calls are used (no throwing std::filesystem calls): every failure,
// a name too long, a loop of symbolic links, a full disk, is a springy::Error naming the path
// and the reason (strerror).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sim/interrupt.h"

namespace springy {

class AtomicFile {
 public:
  // Creates the temporary file at once, so an unwritable target is reported before any work.
  // A target that is a symbolic link keeps the link: the temporary file is made beside the
  // link's final target and renamed over it. A replaced file keeps its permission bits; a new
  // one gets 0666 less the umask. Refuses a target that is a directory, not a regular file, or
  // the same file as one of `inputs` (the files the output is made from, e.g. the scene).
  // Throws springy::Error naming the target.
  explicit AtomicFile(std::string target, const std::vector<std::string>& inputs = {});
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // For writers that open the file by name themselves (FFmpeg, streams); they must report their
  // own write errors, commit() then checks that the data reached the disk and is not empty.
  const std::string& temporaryPath() const { return temporary_; }
  const std::string& target() const { return target_; }
  // Appends to the temporary file. Throws springy::Error naming the target when a write fails
  // (ENOSPC: a full disk, EFBIG: over the file size limit, EIO).
  void write(std::span<const std::uint8_t> bytes);
  void write(std::string_view text) { write({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}); }
  // Verifies the temporary file (fsync, close, size > 0, and all that write() wrote), then
  // renames it over the target. Throws springy::Error naming the target on any failure, and
  // the temporary file is removed.
  void commit();

 private:
  [[noreturn]] void fail(const std::string& what, int error);
  std::string target_;    // as the user named it (for messages)
  std::string resolved_;  // the file that is replaced: target_ with symbolic links followed
  std::string temporary_;
  int registered_ = -1;  // registerTemporary's handle
  int fd_ = -1;
  std::uint64_t written_ = 0;  // bytes through write()
  bool usedWrite_ = false;
  bool committed_ = false;
};

// Throws springy::Error unless `target` is none of `inputs` (the same file, links followed): "TARGET:
// is the input file 'INPUT'; refusing to write over it". An output never replaces what it is made from.
void refuseInputs(const std::string& target, const std::vector<std::string>& inputs);

// For a file a command writes without the user naming it (an export's companions, render's
// SCENE.mp4, frames' stills): an existing `path` is replaced only if springy wrote it, which it
// tells by `mark` within the file's first `within` bytes (an export's header line "# springy
// export"; render/image.h kSpringyMark in springy's videos and stills). Throws springy::Error
// "PATH: exists and was not written by springy ...; `whose`; ...".
void refuseUnlessMarked(const std::string& path, std::string_view mark, std::size_t within, const std::string& whose);
// Files springy writes under names of its own in a folder the user also keeps files in (a study's
// pages in docs/, a sweep's tables): the folder's record ".springy-files" lists each by name with
// its size and a hash of its bytes. refuseUnlessOwned: an existing `path` is replaced only when the
// record lists it as it is (throws springy::Error naming it, `whose` saying who writes the name);
// refuseUnownedIn: before a run, every file of `folder` whose name `writes` would write must be
// so listed (the error lists those that are not); recordOwned: lists `path` as it is now;
// writeOwnedFile: all three around an atomic write.
void refuseUnlessOwned(const std::string& path, const std::string& whose);
void refuseUnownedIn(const std::string& folder, const std::function<bool(const std::string&)>& writes,
                     const std::string& whose);
void recordOwned(const std::string& path);
void writeOwnedFile(const std::string& path, std::string_view text, const std::string& whose);

// A hash of a file's bytes (FNV-1a over 8-byte words, then the tail), 0 when it cannot be read:
// its bytes, not its time, so that a folder copied elsewhere keeps its records.
std::uint64_t contentHash(const std::string& path);
// A name as one word at the end of a line of a record: '%' and every byte below '!' (a line
// break, a leading space) as %XX, so that any name (a report's subfolder is named after its
// scene) reads back as it was.
std::string escapedPath(const std::string& path);
std::string unescapedPath(const std::string& word);

// The first `count` bytes of `path` ("" when it cannot be read).
std::string firstBytes(const std::string& path, std::size_t count);

// Writes `text` to `path` through an AtomicFile (complete or not at all). Throws springy::Error.
void writeFileAtomically(const std::string& path, std::string_view text, const std::vector<std::string>& inputs = {});

// "REASON" for an errno value (strerror), for messages.
std::string errorText(int error);

// True when `path` names a directory (following links); false when it does not exist or cannot
// be examined (the error shows when it is used).
bool isDirectory(const std::string& path);

// Creates the directory `path` and its missing parents (mkdir -p). Throws springy::Error
// "`what` 'PATH': cannot create the directory 'PART': REASON" (e.g. what = "-o").
void makeDirectories(const std::string& path, const std::string& what);

// True when both paths exist and are the same file (same device and inode, links followed).
bool sameFile(const std::string& a, const std::string& b);

// SIGINT, SIGTERM and SIGHUP set a flag instead of killing the process; long loops poll it and
// stop, so temporary files are removed. The signals that end a process at once (SIGQUIT, the
// crashes SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, and the other default-fatal ones) remove the
// temporaries first (registerTemporary), then end it as they would have. SIGPIPE and SIGXFSZ are ignored, so that writing to a
// closed pipe or past the file size limit fails with EPIPE or EFBIG (and is reported) instead
// of killing the process silently mid-write. A signal the parent set to be ignored (nohup) stays
// ignored.
void installInterruptHandler();
// The flag they set: interrupted(), requestInterrupt() (the Python module forwards a
// KeyboardInterrupt to a command it runs on another thread), clearInterrupt(), interruptSignal()
// (sim/interrupt.h).
// The exit status of an interrupted run: 128 + the signal's number, as a shell reports a process
// killed by it (130 for SIGINT, 129 for SIGHUP, 143 for SIGTERM).
int interruptedExitStatus();

// The temporary files and folders that exist now (AtomicFile's, OutputFolder's), so that a signal
// that ends the process at once (SIGQUIT, SIGABRT, SIGSEGV, SIGBUS, ...: installInterruptHandler
// catches them) still removes them before it ends it. registerTemporary returns a handle for
// forgetTemporary (-1 when the table is full: the destructor still removes it on the normal paths).
int registerTemporary(const std::string& path, bool folder);
void forgetTemporary(int handle);

}  // namespace springy

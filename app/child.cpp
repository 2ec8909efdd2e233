#include "app/child.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "app/atomic_file.h"
#include "sim/error.h"

extern char** environ;

namespace springy {

std::string selfExecutable() {
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) throw Error("cannot find springy's own executable (/proc/self/exe): " + error.message());
  return exe.string();
}

// A poll on the children's pidfds (Linux 5.3+; poll is never restarted after a signal handler,
// so an interrupt wakes it), or a 20 ms nap where pidfds are not available.
void waitForAChild(const std::vector<pid_t>& children) {
  std::vector<pollfd> fds;
  for (const pid_t child : children) {
    const int fd = static_cast<int>(::syscall(SYS_pidfd_open, child, 0));
    if (fd < 0) break;
    fds.push_back({fd, POLLIN, 0});
  }
  if (fds.size() == children.size() && !fds.empty()) {
    ::poll(fds.data(), fds.size(), 200);
  } else {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  for (const pollfd& p : fds) ::close(p.fd);
}

std::string findProgram(const std::string& name) {
  if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? name : std::string();
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  for (std::size_t start = 0; start <= dirs.size();) {
    const std::size_t colon = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = dirs.substr(start, colon - start);
    const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    start = colon + 1;
  }
  return {};
}

pid_t startChild(const std::string& exe, const std::vector<std::string>& args, const std::string& directory,
                 int output) {
  std::vector<std::string> all = {exe};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  // The child's errno when it cannot start comes back through a pipe that execve closes.
  int report[2] = {-1, -1};
  if (::pipe2(report, O_CLOEXEC) != 0) throw Error("cannot start " + exe + ": " + errorText(errno));
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Only async-signal-safe calls from here to execve: this process may have other threads.
    // PR_SET_PDEATHSIG: SIGTERM when springy ends (its interrupt handler cleans up); springy may
    // have ended before the call, so the parent is checked after it (then it was reparented).
    // springy's own handlers first go back to the default: a SIGTERM caught here before execve
    // would only set springy's flag in this copy and be lost for the program started. SIGPIPE and
    // SIGXFSZ, which springy ignores for its own writes, are the program's to handle.
    struct sigaction byDefault {};
    byDefault.sa_handler = SIG_DFL;
    for (const int s : {SIGINT, SIGTERM, SIGPIPE, SIGXFSZ}) ::sigaction(s, &byDefault, nullptr);
    struct sigaction hangup {};
    if (::sigaction(SIGHUP, nullptr, &hangup) == 0 && hangup.sa_handler != SIG_IGN) {  // nohup: stays ignored
      ::sigaction(SIGHUP, &byDefault, nullptr);
    }
    if (::prctl(PR_SET_PDEATHSIG, SIGTERM) != 0 || ::getppid() != parent) ::_exit(127);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    int error = 0;
    if (output >= 0 && (::dup2(output, STDOUT_FILENO) < 0 || ::dup2(output, STDERR_FILENO) < 0)) error = errno;
    if (error == 0 && !directory.empty() && ::chdir(directory.c_str()) != 0) error = errno;
    if (error == 0) {
      ::execve(exe.c_str(), argv.data(), environ);
      error = errno;
    }
    const ssize_t written = ::write(report[1], &error, sizeof error);
    (void)written;
    ::_exit(127);
  }
  const int forkError = errno;
  ::close(report[1]);
  if (pid < 0) {
    ::close(report[0]);
    throw Error("cannot start " + exe + ": " + errorText(forkError));
  }
  int error = 0;
  ssize_t n = 0;
  do {
    n = ::read(report[0], &error, sizeof error);
  } while (n < 0 && errno == EINTR);
  ::close(report[0]);
  if (n == static_cast<ssize_t>(sizeof error)) {
    ::waitpid(pid, nullptr, 0);
    throw Error("cannot start " + exe + (directory.empty() ? "" : " in " + directory) + ": " + errorText(error));
  }
  return pid;
}

namespace {

// Waits for the child `pid` to end, passing an interrupt of this process on to it once; returns
// its exit status (128 + the signal's number if a signal ended it).
int awaitChild(pid_t pid, const std::string& exe) {
  bool passedOn = false;
  for (;;) {
    int status = 0;
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) {
      if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
      return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
    }
    if (done < 0 && errno != EINTR) throw Error("waiting for " + exe + ": " + errorText(errno));
    if (interrupted() && !passedOn) {
      ::kill(pid, interruptSignal());
      passedOn = true;
    }
    waitForAChild({pid});
  }
}

}  // namespace

int runChild(const std::string& exe, const std::vector<std::string>& args, const std::string& directory) {
  return awaitChild(startChild(exe, args, directory), exe);
}

ChildOutput runCapturing(const std::string& exe, const std::vector<std::string>& args, const std::string& directory) {
  int pipe[2] = {-1, -1};
  if (::pipe2(pipe, O_CLOEXEC) != 0) throw Error("cannot start " + exe + ": " + errorText(errno));
  pid_t pid = -1;
  try {
    pid = startChild(exe, args, directory, pipe[1]);
  } catch (...) {
    ::close(pipe[0]);
    ::close(pipe[1]);
    throw;
  }
  ::close(pipe[1]);
  // Read to the end (the child's exit, or its streams closed), waking every 200 ms to pass an
  // interrupt on: the child then ends, and so does its output.
  ChildOutput result;
  bool passedOn = false;
  for (;;) {
    pollfd p{pipe[0], POLLIN, 0};
    if (::poll(&p, 1, 200) > 0) {
      char buffer[4096];
      const ssize_t n = ::read(pipe[0], buffer, sizeof buffer);
      if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) break;
      if (n > 0) result.output.append(buffer, static_cast<std::size_t>(n));
    }
    if (interrupted() && !passedOn) {
      ::kill(pid, interruptSignal());
      passedOn = true;
    }
  }
  ::close(pipe[0]);
  result.status = awaitChild(pid, exe);
  return result;
}

}  // namespace springy

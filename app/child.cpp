#include "app/child.h"

#include <poll.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
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

int runChild(const std::string& exe, const std::vector<std::string>& args) {
  std::vector<std::string> all = {exe};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (const int error = posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ); error != 0) {
    throw Error("cannot start " + exe + ": " + errorText(error));
  }
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

}  // namespace springy

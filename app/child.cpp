#include "app/child.h"

#include <poll.h>
#include <spawn.h>
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

int runChild(const std::string& exe, const std::vector<std::string>& args, const std::string& directory) {
  std::vector<std::string> all = {exe};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!directory.empty()) posix_spawn_file_actions_addchdir_np(&actions, directory.c_str());
  pid_t pid = 0;
  const int error = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw Error("cannot start " + exe + ": " + errorText(error));
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

// A springy process started with fork/exec, so that a test can limit its file sizes, signal it and
// read what it prints while it runs (tests that need SPRINGY_BINARY defined).
#pragma once

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

namespace springy::test {

using Clock = std::chrono::steady_clock;

struct Result {
  int status = -1;   // exit status, -1 when killed by a signal
  int killedBy = 0;  // the signal that killed it
  std::string output;
  long maxRssKiB = 0;  // the process's peak resident memory (getrusage's ru_maxrss)
};

class Springy {
 public:
  struct Options {
    rlim_t fileSizeLimit = RLIM_INFINITY;  // RLIMIT_FSIZE in bytes: a "full disk" without mounting
    bool ignoreXfsz = false;               // start with SIGXFSZ ignored (`trap '' XFSZ`)
    bool closedStdout = false;             // stdout a pipe whose reader has gone
  };

  Springy(const std::vector<std::string>& args, Options options) {
    std::vector<std::string> all{SPRINGY_BINARY};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    // The output through a pipe, not a file: the file size limit would cut a log file short.
    // Close-on-exec everywhere: the child keeps only what it dup2s onto stdout and stderr (so the
    // closed-stdout pipe has no reader at all).
    int out[2] = {-1, -1}, closed[2] = {-1, -1};
    if (::pipe2(out, O_CLOEXEC) != 0) ADD_FAILURE() << "pipe";
    if (options.closedStdout && ::pipe2(closed, O_CLOEXEC) != 0) ADD_FAILURE() << "pipe";
    pid_ = ::fork();
    if (pid_ == 0) {
      // The default dispositions, whatever the test runner inherited (nohup): springy must set its
      // own. Only async-signal-safe calls between fork and exec.
      for (int s : {SIGHUP, SIGINT, SIGTERM, SIGPIPE, SIGXFSZ}) ::signal(s, SIG_DFL);
      if (options.ignoreXfsz) ::signal(SIGXFSZ, SIG_IGN);
      if (options.fileSizeLimit != RLIM_INFINITY) {
        const rlimit limit{options.fileSizeLimit, options.fileSizeLimit};
        ::setrlimit(RLIMIT_FSIZE, &limit);
      }
      ::dup2(out[1], STDERR_FILENO);
      ::dup2(options.closedStdout ? closed[1] : out[1], STDOUT_FILENO);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(out[1]);
    output_ = out[0];
    ::fcntl(output_, F_SETFL, O_NONBLOCK);
    if (options.closedStdout) {
      ::close(closed[0]);  // nobody reads: the child's writes to stdout fail with EPIPE
      ::close(closed[1]);
    }
  }
  Springy(const Springy&) = delete;
  Springy& operator=(const Springy&) = delete;
  ~Springy() {
    if (pid_ > 0 && !done_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (output_ >= 0) ::close(output_);
  }

  void signal(int s) const { ::kill(pid_, s); }
  pid_t pid() const { return pid_; }

  // Waits at most `timeout` (then kills it: a hang is a failure).
  Result wait(double timeout = 60.0) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
    int raw = 0;
    rusage usage{};
    for (;;) {
      drain();
      const pid_t r = ::wait4(pid_, &raw, WNOHANG, &usage);
      if (r == pid_) break;
      if (Clock::now() > deadline) {
        ::kill(pid_, SIGKILL);
        ::wait4(pid_, &raw, 0, &usage);
        ADD_FAILURE() << "springy did not finish within " << timeout << " s";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    done_ = true;
    drain();
    return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, WIFSIGNALED(raw) ? WTERMSIG(raw) : 0, text_, usage.ru_maxrss};
  }
  // What it printed so far.
  const std::string& output() {
    drain();
    return text_;
  }

 private:
  // Reads what the child wrote so far (the pipe must not fill up and block it).
  void drain() {
    char buffer[4096];
    for (;;) {
      const ssize_t n = ::read(output_, buffer, sizeof buffer);
      if (n <= 0) return;
      text_.append(buffer, static_cast<std::size_t>(n));
    }
  }
  pid_t pid_ = -1;
  int output_ = -1;
  bool done_ = false;
  std::string text_;
};

}  // namespace springy::test

// springy app: other processes springy runs (the sweep's local runner and its Slurm submission;
// `render`, `frames` and `report`, which run springy-render beside springy; gnuplot).
//
// Never through a shell: a program and its arguments go to execve as they are, so no name (a
// scene file, an output folder: "Bob's $HOME; ball\n.toml") is ever parsed as a command. Every
// child dies with springy: it gets SIGTERM (its interrupt handler removes its temporary files and
// it ends) when springy ends, however springy ends (kill -9 included), so no orphan writes an
// output later.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace springy {

// This process's executable (/proc/self/exe). Throws springy::Error.
std::string selfExecutable();

// Sleeps until one of the children may have exited, a signal arrived, or 200 ms passed.
void waitForAChild(const std::vector<pid_t>& children);

// Starts `exe` (a path) with `args` (without the program's name) in `directory` (empty: this
// process's), its standard output and error on `output` (a file descriptor; -1: this process's).
// The child gets SIGTERM when the thread that started it ends (prctl PR_SET_PDEATHSIG: call it
// from the main thread), and does not start at all when this process is gone before it could ask
// for that. Throws springy::Error when the child cannot start (the reason execve gave).
pid_t startChild(const std::string& exe, const std::vector<std::string>& args, const std::string& directory = "",
                 int output = -1);

// Runs `exe` with `args` as a child sharing this process's standard streams (startChild) and
// returns its exit status (128 + the signal's number if a signal ended it). An interrupt of this
// process (SIGINT, SIGTERM, SIGHUP) is passed on to the child, which cleans up and ends. Throws
// springy::Error when the child cannot start.
int runChild(const std::string& exe, const std::vector<std::string>& args, const std::string& directory = "");

// What a child printed and how it ended (runCapturing).
struct ChildOutput {
  int status = 0;      // exit status, 128 + the signal's number if a signal ended it
  std::string output;  // its standard output and error, interleaved as written
};

// Runs `exe` with `args` (startChild) and collects its standard output and error through a pipe
// (sbatch's job id). Passes an interrupt on as runChild does. Throws springy::Error when it
// cannot start.
ChildOutput runCapturing(const std::string& exe, const std::vector<std::string>& args,
                         const std::string& directory = "");

// The program `name` as found on PATH (as a shell would run it), or "" when there is none.
std::string findProgram(const std::string& name);

}  // namespace springy

// springy app: other springy processes (the sweep's local runner; `render` and `frames`, which
// run springy-render beside springy).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace springy {

// This process's executable (/proc/self/exe). Throws springy::Error.
std::string selfExecutable();

// Sleeps until one of the children may have exited, a signal arrived, or 200 ms passed.
void waitForAChild(const std::vector<pid_t>& children);

// Runs `exe` (a path) with `args` (without the program's name) as a child sharing this process's
// standard streams, in `directory` (empty: this process's), and returns its exit status (128 +
// the signal's number if a signal ended it). No shell: each argument reaches the program as it
// is, whatever it holds. An interrupt of this process (SIGINT, SIGTERM, SIGHUP) is passed on to
// the child, which cleans up and ends. Throws springy::Error when the child cannot start.
int runChild(const std::string& exe, const std::vector<std::string>& args, const std::string& directory = "");

// The program `name` as found on PATH (as a shell would run it), or "" when there is none.
std::string findProgram(const std::string& name);

}  // namespace springy

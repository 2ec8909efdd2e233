// Runs the springy binary as a user would (tests that need SPRINGY_BINARY defined).
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

namespace springy::test {

struct CommandResult {
  int status;           // exit status, -1 if it did not exit normally
  std::string output;   // stdout and stderr
};

inline CommandResult runSpringy(const std::string& args) {
  const std::string command = std::string(SPRINGY_BINARY) + " " + args + " 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  CommandResult r{-1, ""};
  std::array<char, 4096> buffer;
  while (fgets(buffer.data(), static_cast<int>(buffer.size()), pipe.get())) r.output += buffer.data();
  const int raw = pclose(pipe.release());
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

}  // namespace springy::test

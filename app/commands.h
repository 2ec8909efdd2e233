// springy app: the subcommands.
#pragma once

#include <string>
#include <vector>

#include "app/runner.h"

namespace springy {

struct CheckOptions {
  std::vector<std::string> scenes;
  RunOverrides overrides;
  std::string trace;  // CSV path, empty for none
};
int runCheck(const CheckOptions& options);

}  // namespace springy

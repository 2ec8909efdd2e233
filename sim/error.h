// springy: the one exception type for user errors (scene files, mesh files, command line,
// output paths). Its message is complete and ready to print: it names the file and line, or
// the offending vertex or edge. Programmer errors are asserts, not exceptions.
#pragma once

#include <stdexcept>
#include <string>

namespace springy {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace springy

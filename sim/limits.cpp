#include "sim/limits.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "sim/error.h"

namespace springy {

std::uintmax_t checkInputFile(const std::string& path, std::uintmax_t maxBytes, const char* what) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) {
    throw Error(path + ": cannot open the " + what + ": " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) throw Error(path + ": is a directory, expected a " + what);
  if (!S_ISREG(st.st_mode)) {
    throw Error(path + ": is not a regular file (a pipe, socket or device), expected a " + what);
  }
  if (::access(path.c_str(), R_OK) != 0) {
    throw Error(path + ": cannot read the " + what + ": " + std::strerror(errno));
  }
  const auto size = static_cast<std::uintmax_t>(st.st_size);
  if (size > maxBytes) {
    throw Error(path + ": the " + what + " is " + std::to_string(size >> 20) + " MiB, more than the limit of " +
                std::to_string(maxBytes >> 20) + " MiB");
  }
  return size;
}

}  // namespace springy

// libFuzzer target: a mesh file through readMeshFile, weldVertices, loadClosedMesh and
// simplifyMesh (fuzz/README.md). The first input byte picks the file's extension
// (fuzz/fuzz_inputs.h); the rest is written to a file in a private temporary directory, since
// the readers take a path.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz/fuzz_inputs.h"

namespace {

// A directory of this process's own (mkdtemp), removed at normal exit. A crash leaves it behind
// in $TMPDIR (or /tmp): springy-fuzz-mesh-*.
class PrivateDir {
 public:
  PrivateDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/springy-fuzz-mesh-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) {
      std::perror("fuzz_mesh: mkdtemp");
      std::abort();
    }
    path_ = pattern;
  }
  ~PrivateDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  PrivateDir(const PrivateDir&) = delete;
  PrivateDir& operator=(const PrivateDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  springy::fuzz::defaultCrashSignalsInForkedChildren();
  static const PrivateDir dir;
  if (size == 0) return 0;
  const std::string file = dir.path() + "/input." + std::string(springy::fuzz::meshExtension(data[0]));
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    if (!out) {
      std::perror("fuzz_mesh: writing the input file");
      std::abort();
    }
  }
  springy::fuzz::runMeshFile(file);
  std::remove(file.c_str());
  return 0;
}

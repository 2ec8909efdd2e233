// libFuzzer target: a scene file's text through parseScene and buildModel (fuzz/README.md).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  springy::fuzz::defaultCrashSignalsInForkedChildren();
  static const std::string path = springy::fuzz::scenePath(SPRINGY_SOURCE_DIR);
  springy::fuzz::runScene(std::string(reinterpret_cast<const char*>(data), size), path);
  return 0;
}

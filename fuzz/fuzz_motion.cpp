// libFuzzer target: a scene file's text through parseScene, makeWorld and a few steps, so that
// motion tables, pin tracks and releases and [[attach]] springs run (fuzz/README.md).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  springy::fuzz::defaultCrashSignalsInForkedChildren();
  static const std::string path = springy::fuzz::scenePath(SPRINGY_SOURCE_DIR);
  springy::fuzz::runSceneSteps(std::string(reinterpret_cast<const char*>(data), size), path);
  return 0;
}

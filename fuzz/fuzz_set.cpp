// libFuzzer target: `--set KEY=VALUE` settings over one of the repository's scenes, as the
// command line applies them (loadSceneSetting), then buildModel (fuzz/README.md).
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  springy::fuzz::defaultCrashSignalsInForkedChildren();
  springy::fuzz::runSettings(SPRINGY_SOURCE_DIR, data, size);
  return 0;
}

// Not a test: composes a scene's stills beside the original project's (issue 17) for
// docs/gallery/NAME_vs_original.png (scripts/gallery.sh runs it). The original's image (a JPEG
// or PNG: its eight stills in a grid) on top, ours (springy frames --sheet-only) below, each
// labelled. Written to a temporary name beside the output and renamed when complete.
// Usage: vs_original ORIGINAL OURS OUT.png "original label" "our label"
#include <unistd.h>
#include <cstdio>
#include <filesystem>
#include <string>

#include "render/error.h"
#include "render/image.h"

using namespace springy::render;

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: vs_original ORIGINAL OURS OUT.png ORIGINAL_LABEL OUR_LABEL\n");
    return 1;
  }
  try {
    const Image original = readPng(argv[1]), ours = readPng(argv[2]);
    ContactSheetOptions o;
    o.columns = 1;
    const Image sheet = makeContactSheet({original, ours}, {argv[4], argv[5]}, o);
    const std::filesystem::path out = argv[3];
    const std::filesystem::path tmp =
        out.parent_path() / ("." + out.filename().string() + ".tmp-" + std::to_string(getpid()));
    try {
      writePng(tmp.string(), sheet);
      std::filesystem::rename(tmp, out);
    } catch (...) {
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);
      throw;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vs_original: %s\n", e.what());
    return 1;
  }
  return 0;
}

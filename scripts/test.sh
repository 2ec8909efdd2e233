#!/usr/bin/env bash
# Installs what springy and its tests need (both layers of scripts/install-deps.sh), builds
# everything (the programs, the tests, the Python module) and runs the whole test suite (ctest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh --tests
# ON explicitly: a build/ that scripts/demo.sh configured has them OFF in its cache.
bash scripts/build.sh -DSPRINGY_BUILD_TESTS=ON -DSPRINGY_PYTHON=ON "$@"
build_dir=${SPRINGY_BUILD_DIR:-build}
ctest --test-dir "$build_dir" --output-on-failure -j"$(nproc)"

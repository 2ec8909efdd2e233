#!/usr/bin/env bash
# Configures and builds springy into build/ (or $SPRINGY_BUILD_DIR). Extra arguments go to
# CMake's configure step, e.g. -DSPRINGY_SANITIZE=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${SPRINGY_BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build_dir" -j"$(nproc)"

#!/usr/bin/env bash
# Configures and builds springy into build/ (or $SPRINGY_BUILD_DIR). Extra arguments go to
# CMake's configure step, e.g. -DSPRINGY_SANITIZE=ON. $SPRINGY_BUILD_TARGETS, if set, builds only
# those targets (scripts/demo.sh: "springy", which brings springy-render; not the tests).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${SPRINGY_BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
# shellcheck disable=SC2086
cmake --build "$build_dir" -j"$(nproc)" ${SPRINGY_BUILD_TARGETS:+--target $SPRINGY_BUILD_TARGETS}

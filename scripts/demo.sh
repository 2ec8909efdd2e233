#!/usr/bin/env bash
# Installs what building and running springy needs (the first layer of scripts/install-deps.sh),
# builds the programs and renders the default scene to single_sphere.mp4.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# Only the programs: the tests and the Python module are built by scripts/test.sh (same build/),
# which installs what they need.
SPRINGY_BUILD_TARGETS=springy bash scripts/build.sh -DSPRINGY_BUILD_TESTS=OFF -DSPRINGY_PYTHON=OFF
./build/app/springy render scenes/single_sphere.toml -o single_sphere.mp4

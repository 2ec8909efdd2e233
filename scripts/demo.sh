#!/usr/bin/env bash
# Installs what springy needs, builds it and renders the default scene to single_sphere.mp4.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# Only the programs: the tests and the Python module are built by scripts/test.sh (same build/).
SPRINGY_BUILD_TARGETS=springy bash scripts/build.sh
./build/app/springy render scenes/single_sphere.toml -o single_sphere.mp4

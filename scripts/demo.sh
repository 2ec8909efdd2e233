#!/usr/bin/env bash
# Installs what springy needs, builds it and runs the main job on the default scene.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
./build/app/springy check scenes/single_sphere.toml

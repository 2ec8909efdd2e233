#!/usr/bin/env bash
# Installs the Debian 12 packages springy needs: the one list of them, in two layers.
#
#   bash scripts/install-deps.sh           the programs: what building and running springy needs
#                                          (check, render, frames, export, report, sweep, suggest,
#                                          study); scripts/demo.sh
#   bash scripts/install-deps.sh --tests   and what the tests, the Python module, the benchmarks
#                                          and fuzzing add; scripts/test.sh and .ci/run
#
# Each layer installs only what is missing (one apt-get for all of it); the second adds to the first.
set -euo pipefail
cd "$(dirname "$0")/.."

# Building and running springy.
run=(
  build-essential cmake pkg-config
  libeigen3-dev          # sparse linear algebra (implicit integrator)
  libassimp-dev          # mesh import (OBJ, PLY, STL, glTF)
  libtomlplusplus-dev    # scene files
  libcli11-dev           # command line
  nlohmann-json3-dev     # sweeps: manifests, results, check --json
  libmeshoptimizer-dev   # mesh simplification
  libcgal-dev            # simulation proxies: alpha wrapping + remeshing (header-only, GPL-3+)
  libosmesa6-dev         # offscreen OpenGL (Mesa llvmpipe)
  libglm-dev             # camera and transform maths for the renderer
  libstb-dev             # stb_image_write (PNG), stb_truetype (overlay text)
  fonts-dejavu-core      # the overlay font
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev  # MP4 encoding
  libx264-dev            # pulled in by libavcodec; listed so H.264 is never missing
  zlib1g-dev             # report: the 3D replay's frames, deflated
  libcmark-gfm-dev libcmark-gfm-extensions-dev  # report: a study's Markdown pages as HTML
  gnuplot-nox            # report and study: their plots
)

# The tests, the Python module, the benchmarks, fuzzing.
tests=(
  git ca-certificates
  libgtest-dev libgmock-dev   # tests
  libbenchmark-dev       # benchmarks
  time                   # benchmarks: GNU time, peak memory (scripts/bench-export.sh)
  libbullet-dev          # benchmarks: the peer comparison (Bullet soft bodies, bench/bullet)
  munge slurmctld slurmd slurm-client  # sweeps: the Slurm test's single-node cluster (scripts/slurm-local.sh)
  parallel               # sweeps: the README's GNU parallel example, tested
  python3                # tests: a JUnit consumer (tests/junit_check.py, xml.etree)
  python3-dev pybind11-dev python3-numpy  # the Python module (python/, docs/python.md), built by the test command
  python3-pytest python3-pil  # its tests (tests/python): pytest, PNGs read back
  python3-matplotlib     # the example sweep's plot (examples/sweep_error_vs_time.py), run in the tests
  blender                # tests: export round trip, Blender reads the PC2 on the OBJ and the GLB (tests/blender_roundtrip.py)
  python3-vtk9           # tests: export round trip, VTK (ParaView's readers) reads the PVD series
  nodejs                 # tests: the Khronos glTF validator (npm gltf-validator, tests/js); the report viewer's bundle rebuilt and compared (app/report)
  chromium               # tests: the report opened in headless Chromium (tests/js/report_browser.js)
  clang libclang-rt-14-dev llvm  # fuzzing (scripts/fuzz.sh): clang 14, libFuzzer and sanitizer runtimes, llvm-symbolizer
  universal-ctags        # CONTRIBUTING.md: the count of functions over 80 lines
)

packages=("${run[@]}")
case "${1:-}" in
  --tests) packages+=("${tests[@]}") ;;
  "") ;;
  *) echo "install-deps.sh: unknown option '$1' (none, or --tests)" >&2; exit 2 ;;
esac

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
[ "${1:-}" = --tests ] || exit 0

# npm: Debian's package, unless a Node.js that carries its own npm is installed already (the
# nodesource build conflicts with Debian's npm).
if ! command -v npm >/dev/null; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends npm
fi
# npm packages, at the versions each package-lock.json pins, fetched again only when the lock
# changed: three.js and esbuild for the report viewer's bundle (app/report: the test that
# rebuilds it and compares it with the committed one), the glTF validator and playwright-core
# (which drives Debian's chromium) for the tests (tests/js).
for js in app/report tests/js; do
  if ! cmp -s "$js/package-lock.json" "$js/node_modules/.springy-lock" 2>/dev/null; then
    npm ci --prefix "$js" --no-audit --no-fund --loglevel=error
    cp "$js/package-lock.json" "$js/node_modules/.springy-lock"
  fi
done

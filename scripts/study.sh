#!/usr/bin/env bash
# Regenerates docs/accuracy.md, docs/accuracy-contact.md (with their plots) and docs/stability.md:
# the integrators' error against run time before and through contact, and their largest stable
# steps on stiff and extreme cases.
#   scripts/study.sh [BUILD_DIR]      (default: build; a Release build of the springy target)
# Takes about 35 minutes on 2 cores (2026-12-04: the contact study 16.5 min and the stability study
# 13 min, run side by side; the stability study alone 14 min; the accuracy study a few minutes).
# Run on an otherwise idle machine: the wall times are measured.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$build" -j"$(nproc)" --target springy
"$build"/app/springy study accuracy -o docs
# Whole runs through contact; at most 6 s of each scene (every drop and first impacts; the
# bunnies' 25 s would take hours of reference runs).
"$build"/app/springy study contact --max-duration 6 -o docs
"$build"/app/springy study stability -o docs

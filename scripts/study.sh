#!/usr/bin/env bash
# Regenerates docs/accuracy.md, docs/accuracy-contact.md (with their plots) and docs/stability.md:
# the integrators' error against run time before and through contact, and their largest stable
# steps on stiff and extreme cases.
#   scripts/study.sh [BUILD_DIR]      (default: build; a Release build of the springy target)
# Each study gives its independent runs to every core (study.h runInParallel), one after the
# other: on 2 cores (2026-12-08) the accuracy study took 4.4 min (265 s) and the stability study
# 8.5 min (508 s); before, one run at a time, about 15 and 14 min. The run times the pages report
# are each run's thread CPU time, which its neighbour on the other core does not inflate.
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

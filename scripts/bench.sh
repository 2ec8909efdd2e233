#!/usr/bin/env bash
# Runs the simulation benchmarks (bench/bench_sim.cpp, Google Benchmark) and prints medians.
#   scripts/bench.sh [FILTER]     e.g. scripts/bench.sh 'Kernel|Threads'
# Builds in SPRINGY_BUILD_DIR (default build-bench) with -DSPRINGY_BUILD_BENCHMARKS=ON. Run on
# an otherwise idle machine: every figure is a wall time. The repetitions of all benchmarks
# run in random interleaved order, so that ratios compare runs made at the same times.
# Results: docs/benchmarks.md.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${SPRINGY_BUILD_DIR:-build-bench}
extra=()
[ -f "$build_dir/CMakeCache.txt" ] || extra=(-DSPRINGY_RENDER=OFF -DSPRINGY_BUILD_TESTS=OFF)
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSPRINGY_BUILD_BENCHMARKS=ON "${extra[@]}" > /dev/null
cmake --build "$build_dir" -j"$(nproc)" --target bench_sim > /dev/null
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); $(date -u)"
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
"$build_dir"/bench/bench_sim --benchmark_filter="${1:-.}" --benchmark_min_time=0.3 --benchmark_repetitions=5 \
  --benchmark_enable_random_interleaving=true \
  --benchmark_report_aggregates_only=true 2>&1 | grep -E '^BM_.*_median|^Run on|^Load'

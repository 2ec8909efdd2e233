#!/usr/bin/env bash
# Compares two bench_sim binaries (e.g. before and after a change) in one interleaved run:
#   scripts/bench_compare.sh BEFORE AFTER [FILTER] [ROUNDS]
# Each round runs every selected benchmark once in BEFORE, then once in AFTER (the order swaps
# every round), so both see the same machine; prints per benchmark the median wall time of each
# over the rounds and their ratio AFTER / BEFORE. SPRINGY_BUSY=1 keeps the other core busy with
# a spinning shell loop during the run (a user's busy machine). Results: docs/benchmarks.md.
set -euo pipefail
before=$1 after=$2 filter=${3:-.} rounds=${4:-7}
tmp=$(mktemp -d)
busy=
cleanup() { [ -n "$busy" ] && kill "$busy" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
if [ "${SPRINGY_BUSY:-0}" = 1 ]; then (while :; do :; done) & busy=$!; fi
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); $(date -u)"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg); busy other core: ${SPRINGY_BUSY:-0}; rounds: $rounds"
run() {  # binary label
  # Console format (the CSV reporter refuses benchmarks with different counters): name, wall time, unit.
  "$1" --benchmark_filter="$filter" --benchmark_min_time=0.2 --benchmark_color=false 2>/dev/null |
    awk -v label="$2" '$1 ~ /^BM_/ {
      scale = $3 == "ns" ? 1 : $3 == "us" ? 1e3 : $3 == "ms" ? 1e6 : $3 == "s" ? 1e9 : -1
      if (scale > 0) print label, $1, $2 * scale }' >> "$tmp/times"
}
for ((r = 0; r < rounds; ++r)); do
  if ((r % 2 == 0)); then run "$before" before; run "$after" after; else run "$after" after; run "$before" before; fi
done
# Median per (label, benchmark), then the ratio.
sort -k2,2 -k1,1 -k3,3g "$tmp/times" | awk '
  { key = $1 " " $2; v[key, ++n[key]] = $3; names[$2] = 1 }
  function median(key,   c) { c = n[key]; return c % 2 ? v[key, (c + 1) / 2] : (v[key, c / 2] + v[key, c / 2 + 1]) / 2 }
  END {
    printf "%-45s %14s %14s %8s\n", "benchmark (median ns, wall)", "before", "after", "ratio"
    for (name in names) {
      b = median("before " name); a = median("after " name)
      printf "%-45s %14.0f %14.0f %8.3f\n", name, b, a, a / b
    }
  }' | (read -r header; echo "$header"; sort)

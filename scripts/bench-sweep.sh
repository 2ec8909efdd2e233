#!/usr/bin/env bash
# The local runner's speed-up (docs/benchmarks.md, "Sweeps"): a 16-task `check` sweep (4 stiffnesses
# x 4 drags of the single sphere, 10 s each) through `springy sweep` (one task per core, threads
# split between them) against the same 16 tasks one after another, each on one thread
# (`springy run-task --threads 1`). Rounds alternate the two; prints each time and the medians.
# usage: scripts/bench-sweep.sh [ROUNDS]   (default 5; the build in $SPRINGY_BUILD_DIR or build/)
# SPRINGY_BENCH_QUIET=1: start each round only when no other process is running (on a shared
# machine: waits up to 10 minutes a round, then runs anyway).
set -euo pipefail
cd "$(dirname "$0")/.."
springy=$PWD/${SPRINGY_BUILD_DIR:-build}/app/springy
rounds=${1:-5}
work=$(mktemp -d /tmp/springy-bench-sweep.XXXXXX)
trap 'rm -rf "$work"' EXIT
cat >"$work/bench.toml" <<EOF2
scenes = ["$PWD/scenes/single_sphere.toml"]
command = "check"
[set]
duration = 10.0
[grid]
body.strut_period = [0.05, 0.07, 0.09, 0.11]
environment.drag = [0.1, 0.15, 0.2, 0.25]
EOF2
now() { date +%s.%N; }
seq_times=() local_times=()
# True when nothing else has been running for the last 3 s (/proc/loadavg's running count is ours).
quiet() {
  local i
  for i in 1 2 3 4 5 6; do
    [ "$(cut -d' ' -f4 /proc/loadavg | cut -d/ -f1)" -le 1 ] || return 1
    sleep 0.5
  done
}
for r in $(seq "$rounds"); do
  if [ "${SPRINGY_BENCH_QUIET:-0}" = 1 ]; then
    for i in $(seq 600); do quiet && break; sleep 1; done
  fi
  rm -rf "$work/seq" "$work/local"
  "$springy" sweep "$work/bench.toml" -o "$work/seq" --manifest-only >/dev/null
  t0=$(now)
  for i in $(seq 0 15); do "$springy" run-task "$work/seq/manifest.jsonl" --index "$i" --threads 1 >/dev/null 2>&1; done
  t1=$(now)
  "$springy" sweep "$work/bench.toml" -o "$work/local" >/dev/null
  t2=$(now)
  "$springy" gather "$work/seq/manifest.jsonl" >/dev/null
  cmp -s "$work/seq/table.csv" "$work/local/table.csv" || { echo "the two tables differ" >&2; exit 1; }
  seq_times+=("$(awk "BEGIN {printf \"%.2f\", $t1 - $t0}")")
  local_times+=("$(awk "BEGIN {printf \"%.2f\", $t2 - $t1}")")
  echo "round $r: one after another ${seq_times[-1]} s, local runner ${local_times[-1]} s (load average $(cut -d' ' -f1-3 /proc/loadavg))"
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
ms=$(median "${seq_times[@]}")
ml=$(median "${local_times[@]}")
echo "median: one after another $ms s, local runner $ml s, speed-up $(awk "BEGIN {printf \"%.2f\", $ms / $ml}") ($(nproc) cores)"

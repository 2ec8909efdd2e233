#!/usr/bin/env bash
# Compares two springy binaries (e.g. a commit with and without a change) on whole `check` runs,
# in one interleaved run, as scripts/bench_compare.sh does for bench_sim:
#   scripts/bench-check-ab.sh BEFORE AFTER SCENE DURATION [ROUNDS]
# Each round runs `check SCENE --threads 1 --duration DURATION` once with each binary (the order
# swaps every round); prints the median wall time of each and the ratio AFTER / BEFORE.
# SPRINGY_BUSY=1 keeps the other core busy with a spinning loop. Results: docs/benchmarks.md.
set -euo pipefail
before=$1 after=$2 scene=$3 duration=$4 rounds=${5:-5}
busy=
cleanup() { [ -n "$busy" ] && kill "$busy" 2>/dev/null; true; }
trap cleanup EXIT
if [ "${SPRINGY_BUSY:-0}" = 1 ]; then (while :; do :; done) & busy=$!; fi
once() {  # binary -> wall seconds
  local s e
  s=$(date +%s.%N)
  "$1" check "$scene" --threads 1 --duration "$duration" >/dev/null 2>&1
  e=$(date +%s.%N)
  awk -v s="$s" -v e="$e" 'BEGIN {print e - s}'
}
a=() b=()
for ((r = 0; r < rounds; ++r)); do
  if ((r % 2 == 0)); then a+=("$(once "$before")"); b+=("$(once "$after")"); else
    b+=("$(once "$after")"); a+=("$(once "$before")"); fi
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
ma=$(median "${a[@]}") mb=$(median "${b[@]}")
printf '%s %s s, busy %s: before %.3f s, after %.3f s, after/before %.3f (medians of %d, interleaved)\n' \
  "$scene" "$duration" "${SPRINGY_BUSY:-0}" "$ma" "$mb" "$(awk -v a="$ma" -v b="$mb" 'BEGIN {print b / a}')" "$rounds"

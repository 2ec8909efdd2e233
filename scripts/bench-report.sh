#!/usr/bin/env bash
# springy report against springy render of the same scene, both on one thread, one after the
# other in each round (docs/report.md, "Sizes and times"). Prints one line per run and the
# medians; with BASE=DIR (another build's app/ folder, e.g. of an older commit) its two runs are
# interleaved with this build's in every round.
#
#   scripts/bench-report.sh ROUNDS SCENE.toml...        BUSY=1: a busy loop on another core
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:?rounds}
shift
builds=(build/app)
[ -n "${BASE:-}" ] && builds=("$BASE" build/app)
out=$(mktemp -d)
trap 'rm -rf "$out"; [ -n "${busy:-}" ] && kill "$busy" 2>/dev/null || true' EXIT
if [ -n "${BUSY:-}" ]; then (while :; do :; done) & busy=$!; fi
log="$out/runs"
for ((r = 1; r <= rounds; r++)); do
  for scene in "$@"; do
    for b in "${builds[@]}"; do
      for command in render report; do
        rm -rf "$out/r" "$out/v.mp4"
        start=$(date +%s.%N)
        if [ "$command" = render ]; then
          "$b/springy" render "$scene" -o "$out/v.mp4" --threads 1 > "$out/said" 2>&1 || status=$?
        else
          "$b/springy" report "$scene" -o "$out/r" --threads 1 > "$out/said" 2>&1 || status=$?
        fi
        if [ "${status:-0}" != 0 ]; then
          echo "bench-report.sh: $b/springy $command $scene failed (exit $status):" >&2
          tail -5 "$out/said" >&2
          exit 1
        fi
        end=$(date +%s.%N)
        echo "$b $command $(basename "$scene" .toml) $(echo "$end - $start" | bc)" | tee -a "$log"
      done
    done
  done
done
echo "medians (s):"
sort -k1,1 -k3,3 -k2,2 "$log" | awk '{k = $1 " " $3 " " $2; v[k] = v[k] " " $4} END {for (k in v) print k, v[k]}' |
  while read -r build scene command times; do
    printf '%s %s %s %s\n' "$build" "$scene" "$command" "$(printf '%s\n' $times | sort -n | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}')"
  done | sort

#!/usr/bin/env bash
# What `springy export` costs over `springy check` of the same run (issue 42: at most 10%), and
# that its memory does not grow with the frames. Results: docs/benchmarks.md, "Export".
#
#   bash scripts/bench-export.sh overhead ROUNDS SCENE [ARGS...]
#       check, export .pc2, .glb and .pvd of SCENE (ARGS passed to each: --duration, --fps, ...),
#       interleaved in each round; prints every run's wall time and the medians with their ratio to
#       check's. SPRINGY_BENCH_BUSY=1: a busy loop holds the other core meanwhile, as a user's
#       machine has.
#   bash scripts/bench-export.sh memory
#       the pile with 642-vertex balls (15,408 vertices), 600 frames (2.5 s at 240 frames a second):
#       check and each export once, their wall times and peak resident memory (GNU time's %M).
# Needs a Release build in build/ (scripts/build.sh) and GNU time (/usr/bin/time).
set -euo pipefail
cd "$(dirname "$0")/.."
springy=./build/app/springy
out=$(mktemp -d /tmp/springy-bench-export.XXXXXX)
busy=
cleanup() {
  [ -n "$busy" ] && kill "$busy" 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT

# One run: prints "seconds peak_KiB".
measure() {
  /usr/bin/time -f "%e %M" -o "$out/time" "$@" >"$out/log" 2>&1 || { cat "$out/log"; exit 1; }
  cat "$out/time"
}

median() { sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }

case "${1:-}" in
  overhead)
    rounds=$2
    scene=$3
    shift 3
    if [ "${SPRINGY_BENCH_BUSY:-0}" = 1 ]; then
      ( while :; do :; done ) &
      busy=$!
      echo "a busy loop (pid $busy) holds a core"
    fi
    variants=(check pc2 glb pvd)
    for ((r = 1; r <= rounds; ++r)); do
      line="round $r:"
      for v in "${variants[@]}"; do
        if [ "$v" = check ]; then
          t=$(measure "$springy" check "$scene" "$@")
        else
          t=$(measure "$springy" export "$scene" -o "$out/run.$v" "$@")
        fi
        echo "${t%% *}" >>"$out/$v.times"
        line+=" $v ${t%% *} s"
      done
      echo "$line"
    done
    base=$(median <"$out/check.times")
    for v in "${variants[@]}"; do
      m=$(median <"$out/$v.times")
      awk -v v="$v" -v m="$m" -v b="$base" 'BEGIN { printf "median %-5s %7.2f s  %.3fx check\n", v, m, m / b }'
    done
    ;;
  memory)
    scene="$out/pile15k.toml"
    # The shipped pile's balls one subdivision finer: 24 x 642 vertices.
    sed 's/^subdivisions = 2 .*/subdivisions = 3/' scenes/pile.toml >"$scene"
    args=(--duration 2.5 --set render.fps=240)
    t=$(measure "$springy" check "$scene" "${args[@]}")
    echo "check: ${t%% *} s, peak ${t##* } KiB"
    for v in pc2 glb pvd; do
      t=$(measure "$springy" export "$scene" -o "$out/run.$v" "${args[@]}")
      size=$(du -sk --apparent-size "$out" | cut -f1)
      echo "export .$v: ${t%% *} s, peak ${t##* } KiB, output $((size / 1024)) MiB"
      grep -h "frames (100%)" "$out/log" | tail -1
      rm -rf "$out/run" "$out"/run.*
    done
    ;;
  *)
    echo "usage: bench-export.sh overhead ROUNDS SCENE [ARGS...] | memory" >&2
    exit 2
    ;;
esac

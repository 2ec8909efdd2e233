#!/usr/bin/env bash
# Fuzzes the scene parser, the mesh loader, what moves on its own and --set (fuzz/README.md).
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]      TARGET: scene, mesh, motion, set (default: all
#                                              four); SECONDS: 60
#
# Builds the libFuzzer targets with clang under ASan + UBSan in build-fuzz/ (or
# $SPRINGY_FUZZ_BUILD_DIR), then runs each target for SECONDS, one after the other, from the
# committed seed corpus fuzz/corpus/TARGET with a fixed seed. New corpus entries and crash
# files go to a scratch directory ($SPRINGY_FUZZ_OUT, default build-fuzz/runs/DATE-TIME/TARGET/
# {corpus,artifacts}), never into the committed corpus. libFuzzer runs in fork mode and keeps
# going past a crash, so one run reports every crash it finds. Exits non-zero if any target
# crashed, leaked, timed out (-timeout=10) or ran out of memory (-rss_limit_mb=2048), printing
# each reproducer's path. Extra libFuzzer flags: $SPRINGY_FUZZ_ARGS; seed: $SPRINGY_FUZZ_SEED.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
[ $# -gt 0 ] && shift
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene mesh motion set)
build_dir=${SPRINGY_FUZZ_BUILD_DIR:-build-fuzz}
out=${SPRINGY_FUZZ_OUT:-$build_dir/runs/$(date +%Y%m%d-%H%M%S)}
seed=${SPRINGY_FUZZ_SEED:-1}
for t in "${targets[@]}"; do
  case $t in scene | mesh | motion | set) ;; *) echo "fuzz.sh: unknown target '$t' (scene, mesh, motion, set)" >&2; exit 2 ;; esac
done

# Asserts stay on (-O1 -g, no -DNDEBUG): a failed assert on fuzzed input is a bug too.
cmake -S . -B "$build_dir" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DSPRINGY_FUZZ=ON -DSPRINGY_WERROR=OFF \
  -DSPRINGY_RENDER=OFF -DSPRINGY_BUILD_TESTS=OFF >/dev/null
cmake --build "$build_dir" -j"$(nproc)" --target "${targets[@]/#/fuzz_}"

# Leak detection stays on for springy's code; assimp's own leaks are suppressed (fuzz/lsan.supp).
# The symbolizer gives crash reports file:line.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:symbolize=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1:symbolize=1}
if command -v llvm-symbolizer >/dev/null; then export ASAN_SYMBOLIZER_PATH=${ASAN_SYMBOLIZER_PATH:-$(command -v llvm-symbolizer)}; fi

failed=()
for t in "${targets[@]}"; do
  dir=$out/$t
  mkdir -p "$dir/corpus" "$dir/artifacts"
  case $t in
    scene) extra=(-dict=fuzz/scene.dict -max_len=16384) ;;
    mesh) extra=(-dict=fuzz/mesh.dict -max_len=32768) ;;
    motion) extra=(-dict=fuzz/motion.dict -max_len=8192) ;;
    set) extra=(-dict=fuzz/set.dict -max_len=1024) ;;
  esac
  echo "== fuzz_$t: ${seconds} s, log $dir/fuzz.log =="
  # The first corpus directory receives new entries; fuzz/corpus/$t is only read.
  # The outer timeout ends a run whose job never returns (a child deadlocked in its timeout
  # handler inside the sanitizer's allocator has been seen); that run counts as failed.
  status=0
  # shellcheck disable=SC2086
  timeout -k 30 "$((seconds + 300))" "$build_dir/fuzz/fuzz_$t" -max_total_time="$seconds" -seed="$seed" -timeout=10 -rss_limit_mb=2048 \
    -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 -print_final_stats=1 -print_funcs=0 \
    -artifact_prefix="$dir/artifacts/" "${extra[@]}" ${SPRINGY_FUZZ_ARGS:-} \
    "$dir/corpus" "fuzz/corpus/$t" >"$dir/fuzz.log" 2>&1 || status=$?
  if [ $status -eq 124 ] || [ $status -eq 137 ]; then
    echo "fuzz_$t did not finish within $((seconds + 300)) s: a job hung (see $dir/fuzz.log)" | tee -a "$dir/fuzz.log"
    touch "$dir/artifacts/timeout-run-did-not-finish"
  fi
  grep -E '^#[0-9]+' "$dir/fuzz.log" | tail -n 1 || true
  # libFuzzer's -timeout is wall-clock time: a job stalled for 10 s by the machine, or by the fork
  # of a mesh reader, leaves a timeout that its input does not cause. A real hang takes as long
  # again alone: each timeout's input is run alone three times, and only one that times out again
  # counts; the others move to unconfirmed/ and are listed (fuzz/README.md, "A note on load").
  for r in "$dir"/artifacts/timeout-*; do
    [ -f "$r" ] && [ "$(basename "$r")" != timeout-run-did-not-finish ] || continue
    again=0
    for _ in 1 2 3; do
      timeout -k 10 60 "$build_dir/fuzz/fuzz_$t" -timeout=10 -rss_limit_mb=2048 -runs=1 "$r" >>"$dir/rerun.log" 2>&1 ||
        again=1
    done
    if [ $again -eq 0 ]; then
      mkdir -p "$dir/unconfirmed"
      mv "$r" "$dir/unconfirmed/"
      echo "fuzz_$t: a timeout whose input runs alone in time, three times (a stall, not a hang): $dir/unconfirmed/$(basename "$r")"
    fi
  done
  mapfile -t found < <(find "$dir/artifacts" -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' \
                                -o -name 'oom-*' \) | sort)
  if [ ${#found[@]} -gt 0 ]; then
    failed+=("$t")
    echo "fuzz_$t FAILED: ${#found[@]} reproducer(s) (reports in $dir/fuzz.log):"
    grep -E 'ERROR: (AddressSanitizer|UndefinedBehaviorSanitizer|LeakSanitizer|libFuzzer)|runtime error:|SUMMARY:' \
      "$dir/fuzz.log" | sed -E 's/==[0-9]+== ?//; s/0x[0-9a-f]+/ADDR/g' | sort | uniq -c | sort -rn | head -n 20 || true
    printf '  %s\n' "${found[@]}"
    echo "Reproduce one: $build_dir/fuzz/fuzz_$t REPRODUCER; group them by cause: fuzz/triage.sh $t $dir/artifacts/*"
  else
    echo "fuzz_$t: no crash ($(find "$dir/corpus" -type f | wc -l) new corpus entries in $dir/corpus)"
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: crashes in: ${failed[*]}" >&2
  exit 1
fi

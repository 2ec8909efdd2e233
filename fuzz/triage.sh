#!/usr/bin/env bash
# Runs fuzz reproducers one by one and groups them by cause: for each distinct signature (the
# sanitizer's or assert's message and the first frames of the stack) it prints the count, one
# reproducer (the smallest) and its stack.
#
#   fuzz/triage.sh TARGET REPRODUCER...      TARGET: scene, mesh, motion, set; needs build-fuzz (scripts/fuzz.sh)
#   fuzz/triage.sh mesh build-fuzz/runs/*/mesh/artifacts/*
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 2 ] || { sed -n '2,7p' "$0" >&2; exit 2; }
target=$1
shift
binary=${SPRINGY_FUZZ_BUILD_DIR:-$root/build-fuzz}/fuzz/fuzz_$target
[ -x "$binary" ] || { echo "triage.sh: $binary not built (run scripts/fuzz.sh 1 $target)" >&2; exit 2; }
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:symbolize=1:fast_unwind_on_malloc=0}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/fuzz/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1:symbolize=1}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for input in "$@"; do
  log=$work/$(basename "$input").log
  timeout 120 "$binary" -timeout=10 -rss_limit_mb=2048 "$input" >"$log" 2>&1
  status=$?
  # Signature: the first report line (addresses and pids removed) and up to four stack frames
  # that are neither the sanitizer's nor libFuzzer's own.
  first=$(grep -m1 -E 'ERROR: |runtime error:|ai_assert|terminate called|Assertion .* failed|out-of-memory|timeout' "$log" |
          sed -E 's/0x[0-9a-f]+//g; s/==[0-9]+==//g; s/\(pid [0-9]+\)//g; s/ +/ /g')
  frames=$(grep -E '^ +#[0-9]+ ' "$log" | grep -v -E '__sanitizer|fuzzer::|libc.so|__pthread|raise|abort|libstdc\+\+|__cxa|std::terminate' |
           head -n 4 | sed -E 's/^ +#[0-9]+ 0x[0-9a-f]+ in //; s/^ +#[0-9]+ 0x[0-9a-f]+ +//; s/ \(BuildId.*//; s/:[0-9]+:[0-9]+$//' | paste -sd '|')
  [ -n "$first" ] || first="no longer reproduces (exit status $status)"
  printf '%s\t%s\t%s\t%s\n' "$first ## $frames" "$(stat -c %s "$input")" "$input" "$log"
done | sort -t$'\t' -k1,1 -k2,2n | awk -F'\t' '
  $1 != sig { if (sig != "") print_group(); sig = $1; n = 0; smallest = $3; lg = $4 }
  { n++ }
  END { if (sig != "") print_group() }
  function print_group() {
    split(sig, parts, " ## ")
    printf "== %d reproducer(s): %s\n   smallest: %s\n", n, parts[1], smallest
    while ((getline line < lg) > 0) {
      if (line !~ /^ +#[0-9]+ / || line ~ /fuzzer::|__sanitizer|libc.so|nptl|stdlib\/abort/) continue
      sub(/ \(BuildId: [0-9a-f]+\)/, "", line)
      print "  " line
      if (line ~ /LLVMFuzzerTestOneInput/) break
    }
    close(lg)
  }'

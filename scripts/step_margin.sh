#!/usr/bin/env bash
# Measures how the stability advisor's at-rest step limit compares with the largest step that
# really survives a whole run (drop, impact, rebound) of each scene given: bisection on --dt
# with one substep, a run counting as stable when `springy check` finishes it (the monitor stops
# a run on NaN, exploding energy or size, or a body crossing a collider).
#
#   scripts/step_margin.sh SCENE...        (prints a Markdown table: docs/step-margin.md)
#
# The corpus of tests/test_corpus.cpp, kept on disk:
#   SPRINGY_CORPUS_KEEP=1 build/tests/test_corpus; scripts/step_margin.sh /tmp/springy_corpus_*/scene.toml
set -euo pipefail
springy=${SPRINGY:-$(dirname "$0")/../build/app/springy}
echo "| scene | vertices | advisor's limit [ms] | largest stable step [ms] | ratio |"
echo "|---|---|---|---|---|"
for scene in "$@"; do
  name=$(sed 's|.*/springy_corpus_[0-9]*_\([^/]*\)/scene.toml$|\1|' <<<"$scene")
  advice=$("$springy" suggest "$scene" --keep-volume 0 2>/dev/null)
  limit=$(sed -n 's/.*largest stable step with the current values: \([0-9.e+-]*\) s.*/\1/p' <<<"$advice" | head -1)
  vertices=$(sed -n "s/.*body '.*' (\([0-9]*\) vertices.*/\1/p" <<<"$advice" | head -1)
  [ -n "$limit" ] || { echo "| $name | | no limit (implicit?) | | |"; continue; }
  stable() { "$springy" check "$scene" --dt "$1" --substeps 1 >/dev/null 2>&1; }
  lo=$(awk -v l="$limit" 'BEGIN { print l / 8 }')
  hi=$(awk -v l="$limit" 'BEGIN { print l * 4 }')
  if ! stable "$lo"; then echo "| $name | $vertices | $(awk -v l="$limit" 'BEGIN{printf "%.4g", l*1e3}') | < $(awk -v l="$lo" 'BEGIN{printf "%.4g", l*1e3}') | |"; continue; fi
  if stable "$hi"; then lo=$hi; else
    for _ in 1 2 3 4 5 6 7; do
      mid=$(awk -v a="$lo" -v b="$hi" 'BEGIN { print sqrt(a * b) }')
      if stable "$mid"; then lo=$mid; else hi=$mid; fi
    done
  fi
  awk -v s="$name" -v n="$vertices" -v l="$limit" -v m="$lo" \
    'BEGIN { printf "| %s | %s | %.4g | %.4g | %.2f |\n", s, n, l * 1e3, m * 1e3, m / l }'
done

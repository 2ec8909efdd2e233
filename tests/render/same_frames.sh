#!/usr/bin/env bash
# Not a test: checks that a change to the renderer leaves every scene's stills as they were.
# Writes `springy frames` stills of scenes/*.toml (8 times over the first DURATION seconds) with
# two springy binaries (each with its springy-render beside it) and compares them byte for byte.
# Exit status 1 and the differing stills listed when any differs.
#
# Usage: tests/render/same_frames.sh BEFORE_SPRINGY AFTER_SPRINGY [DURATION=1.5] [SCENE.toml...]
# e.g. after `git worktree add /tmp/before HEAD~1 && bash /tmp/before/scripts/build.sh` (which
# builds /tmp/before/build): tests/render/same_frames.sh /tmp/before/build/app/springy build/app/springy
set -euo pipefail
if [ $# -lt 2 ]; then
  sed -n '2,9p' "$0" >&2
  exit 2
fi
before=$1 after=$2
duration=${3:-1.5}
shift $(($# < 3 ? $# : 3))
root=$(cd "$(dirname "$0")/../.." && pwd)
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=("$root"/scenes/*.toml)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
mkdir "$out/before" "$out/after"
for side in before after; do
  binary=$before
  [ "$side" = after ] && binary=$after
  "$binary" frames "${scenes[@]}" --duration "$duration" -o "$out/$side" >"$out/$side.log" 2>&1 ||
    { cat "$out/$side.log"; echo "$binary frames failed"; exit 1; }
done
count=0 differ=0
for f in "$out"/before/*.png; do
  count=$((count + 1))
  if ! cmp -s "$f" "$out/after/$(basename "$f")"; then
    echo "differs: $(basename "$f")"
    differ=$((differ + 1))
  fi
done
[ "$(ls "$out/after" | wc -l)" -eq "$count" ] || { echo "the two binaries wrote different sets of stills"; exit 1; }
echo "$count stills of ${#scenes[@]} scenes, $differ differ"
[ "$differ" -eq 0 ]

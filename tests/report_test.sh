#!/usr/bin/env bash
# ctest report_browser: `springy report` end to end, its pages read as a reader reads them.
#   1. a report of three scenes (one that passes, the press whose plate moves, one that blows up),
#      a sweep and a study
#   2. tests/report_check.py: every reference in the folder, the pages' markup, the 3D replay's
#      frames against the point cache `springy export` writes of the same run, the size
#   3. tests/js/report_browser.js: the pages in headless Chromium (Debian's chromium): no console
#      errors, images decoded, the video plays past 6 s and is drawn, the 3D view draws, links open
# usage: report_test.sh SPRINGY SOURCE_DIR
set -euo pipefail
springy=$1
source_dir=$2
work=$(mktemp -d /tmp/springy-report-test.XXXXXX)
trap 'rm -rf "$work"' EXIT
scene=$source_dir/scenes/single_sphere.toml
press=$source_dir/scenes/press.toml   # its plate moves: the replay places it at every frame
run() { echo "+ $*"; "$@"; }

run "$springy" sweep "$source_dir/tests/data/report/sweep.toml" -o "$work/tiny.sweep" > "$work/sweep.log"
mkdir "$work/study"
cp "$source_dir"/docs/accuracy.md "$source_dir"/docs/accuracy-*.png "$source_dir"/docs/accuracy-orders.csv "$work/study/"
# The blown-up scene makes the report exit 1, and the report is still written (it shows the failure).
status=0
run "$springy" report "$scene" "$press" "$source_dir/tests/data/app/unstable.toml" -o "$work/report" --duration 6.5 \
  --width 320 --height 180 --sweep "$work/tiny.sweep" --study "$work/study" > "$work/report.log" 2>&1 || status=$?
tail -n 3 "$work/report.log"
if [ "$status" != 1 ]; then
  echo "FAIL: springy report exited $status, expected 1 (one scene blew up)"
  cat "$work/report.log"
  exit 1
fi
run "$springy" export "$scene" -o "$work/run.pc2" --duration 6.5 > "$work/export.log"
run "$springy" export "$press" -o "$work/press.pc2" --duration 6.5 >> "$work/export.log"
fps=$(sed -n 's/^fps *= *\([0-9.]*\).*/\1/p' "$scene")
press_fps=$(sed -n 's/^fps *= *\([0-9.]*\).*/\1/p' "$press")
/usr/bin/python3 "$source_dir/tests/report_check.py" "$work/report" \
  --replay "$work/report/single_sphere/replay.js" "$work/run.pc2" "$fps" \
  --replay "$work/report/press/replay.js" "$work/press.pc2" "$press_fps" --max-bytes 5000000
if [ ! -x "${SPRINGY_CHROMIUM:-/usr/bin/chromium}" ] || [ ! -d "$source_dir/tests/js/node_modules/playwright-core" ]; then
  echo "skipped: the browser check needs Debian's chromium and tests/js/node_modules (scripts/install-deps.sh)"
  exit 77
fi
run node "$source_dir/tests/js/report_browser.js" "$work/report"

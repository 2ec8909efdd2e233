#!/usr/bin/env bash
# The report viewer's committed bundle (app/report/viewer.bundle.js, embedded in springy) is what
# scripts/bundle-viewer.sh makes of app/report/viewer.js and the pinned three.js today: bundled
# again into a temporary file and compared byte for byte. A viewer.js edited without bundling it
# again fails here, naming the fix.
set -euo pipefail
source_dir=$1
cd "$source_dir"
if [ ! -x app/report/node_modules/.bin/esbuild ]; then
  echo "report_bundle_check: app/report/node_modules is missing: bash scripts/install-deps.sh --tests" >&2
  exit 1
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"app/report/node_modules/.bin/esbuild" app/report/viewer.js --bundle --minify --format=iife --target=es2020 \
  --legal-comments=eof --log-level=warning --outfile="$tmp/viewer.bundle.js"
if ! cmp -s "$tmp/viewer.bundle.js" app/report/viewer.bundle.js; then
  echo "report_bundle_check: app/report/viewer.bundle.js is not the bundle of app/report/viewer.js:" \
       "run scripts/bundle-viewer.sh and commit app/report/viewer.bundle.js" >&2
  exit 1
fi
echo "report_bundle_check: app/report/viewer.bundle.js is the bundle of viewer.js ($(wc -c < app/report/viewer.bundle.js) bytes)"

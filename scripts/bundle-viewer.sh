#!/usr/bin/env bash
# Bundles the report's 3D viewer: app/report/viewer.js with three.js (npm, at the versions
# app/report/package-lock.json pins) by esbuild, into app/report/viewer.bundle.js, the one
# classic script springy embeds (a page opened from a folder cannot load ES modules). The
# bundle is committed, so building springy needs no npm; run this after editing viewer.js or
# the lock, and commit the result. The test `report_viewer_bundle` rebuilds it and fails when
# the committed one differs.
#
#   scripts/bundle-viewer.sh [OUT]     OUT: default app/report/viewer.bundle.js
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-app/report/viewer.bundle.js}
web=app/report
if ! cmp -s "$web/package-lock.json" "$web/node_modules/.springy-lock" 2>/dev/null; then
  command -v npm >/dev/null || { echo "bundle-viewer.sh: npm is not installed (bash scripts/install-deps.sh --tests)" >&2; exit 1; }
  npm ci --prefix "$web" --no-audit --no-fund --loglevel=error
  cp "$web/package-lock.json" "$web/node_modules/.springy-lock"
fi
"$web/node_modules/.bin/esbuild" "$web/viewer.js" --bundle --minify --format=iife --target=es2020 \
  --legal-comments=eof --log-level=warning --outfile="$out"

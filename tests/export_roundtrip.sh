#!/usr/bin/env bash
# ctest export_roundtrip: springy's exports read back by readers nobody in springy wrote.
#   1. ParaView's way (the .pvd collection, each .vtu read by VTK, python3-vtk9): times, fields and
#      their values against springy's trace and the mesh (tests/export_compare.py pvd).
#   2. The Khronos glTF validator (npm gltf-validator, tests/js): the .glb has no errors.
#   3. Blender (headless, Debian's blender): the OBJ with the PC2 on a Mesh Cache modifier, and the
#      GLB, each read back at three frames, equal to the series' points within 1e-5 of each body's
#      size (tests/blender_roundtrip.py, then export_compare.py blender).
# The scene (tests/data/export/roundtrip.toml) has a body drawn with its simulated mesh, a pinned
# one and a user's mesh over a proxy. A round trip whose reader is not installed is skipped with a
# message naming it (exit 77, ctest's "Skipped"), the others still run; scripts/install-deps.sh
# installs them all.
# usage: export_roundtrip.sh SPRINGY SOURCE_DIR
set -euo pipefail
springy=$1
source_dir=$2
work=$(mktemp -d /tmp/springy-export-test.XXXXXX)
trap 'rm -rf "$work"' EXIT
scene=$source_dir/tests/data/export/roundtrip.toml
fps=30
frames="0 27 60"   # the first, one in the bounce, the last (the scene runs 2 s at 30 frames per second)
python=/usr/bin/python3   # Debian's, whose python3-vtk9 and numpy the test reads with
skipped=()

run() { echo "+ $*"; "$@"; }
run "$springy" export "$scene" -o "$work/run.pvd" --trace "$work/trace.csv" >"$work/pvd.log"
run "$springy" export "$scene" -o "$work/run.pc2" >"$work/pc2.log"
run "$springy" export "$scene" -o "$work/run.glb" >"$work/glb.log"
grep -h "exported:" "$work"/*.log

if "$python" -c "import vtk, numpy" 2>/dev/null; then
  run "$python" "$source_dir/tests/export_compare.py" pvd "$work/run.pvd" "$work/trace.csv" $fps
else
  skipped+=("ParaView's series read by VTK: $python has no vtk or numpy (Debian python3-vtk9, python3-numpy)")
fi

if command -v node >/dev/null && [ -d "$source_dir/tests/js/node_modules/gltf-validator" ]; then
  run node "$source_dir/tests/js/validate_gltf.js" "$work/run.glb"
else
  skipped+=("the Khronos glTF validator: no node, or no tests/js/node_modules (npm ci --prefix tests/js)")
fi

if command -v blender >/dev/null && "$python" -c "import vtk, numpy" 2>/dev/null; then
  # Blender's own output goes to a log, shown only when it fails.
  if ! blender -b --factory-startup --python-exit-code 1 --python "$source_dir/tests/blender_roundtrip.py" -- \
      --obj "$work/run.obj" --pc2 "$work/run.pc2" --glb "$work/run.glb" --fps $fps --frames $frames \
      --out "$work/blender.json" >"$work/blender.log" 2>&1; then
    cat "$work/blender.log"
    echo "export_roundtrip: FAILED: Blender did not read the exports" >&2
    exit 1
  fi
  run "$python" "$source_dir/tests/export_compare.py" blender "$work/run.pvd" "$work/blender.json"
else
  skipped+=("Blender's round trip: no blender (Debian blender) or no VTK to compare with")
fi

if [ ${#skipped[@]} -gt 0 ]; then
  for s in "${skipped[@]}"; do echo "export_roundtrip: SKIPPED $s; scripts/install-deps.sh installs it" >&2; done
  exit 77
fi
echo "export_roundtrip: every reader agrees"

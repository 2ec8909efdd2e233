#!/usr/bin/env bash
# ctest export_roundtrip: springy's exports read back by readers nobody in springy wrote.
#   1. ParaView's way (the .pvd collection, each .vtu read by VTK, python3-vtk9): times, fields and
#      their values against springy's trace and the mesh (tests/export_compare.py pvd).
#   2. The Khronos glTF validator (npm gltf-validator, tests/js): the .glb has no errors.
#   3. Blender (headless, Debian's blender): the OBJ with the PC2 on a Mesh Cache modifier, and the
#      GLB, each read back at three frames, equal to the series' points within 1e-5 of each body's
#      size (tests/blender_roundtrip.py, then export_compare.py blender).
# The scene (tests/data/export/roundtrip.toml) has a body drawn with its simulated mesh, a pinned
# one and a user's mesh over a proxy. Then two scenes where something moves: the press
# (scenes/press.toml, 2 s), whose plate comes down, and the cape (scenes/cape.toml, 1 s), whose bar
# (a prop) turns: each moving mesh's own series read by VTK (a rigid motion, at the bodies' times),
# the validator on their .glb, Blender's OBJ + caches and GLB against the series at three frames,
# and the GLB's plate object placed at the keyed heights (0 at frame 0, -0.7 m held from 1.5 s:
# frame 54). A round trip whose reader is not installed is skipped with a
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
# The scenes that move: name, duration, Blender's frames.
moving=("press 2 0 30 54"    # at rest, on the way down (1 s), held at the bottom (1.8 s)
        "cape 1 0 15 30")    # the bar a quarter and half a turn on
for m in "${moving[@]}"; do
  read -r name duration _ <<<"$m"
  for format in pvd pc2 glb; do
    run "$springy" export "$source_dir/scenes/$name.toml" -o "$work/$name.$format" --duration "$duration" \
      >"$work/$name-$format.log"
  done
done
grep -h "exported:" "$work"/*.log

if "$python" -c "import vtk, numpy" 2>/dev/null; then
  run "$python" "$source_dir/tests/export_compare.py" pvd "$work/run.pvd" "$work/trace.csv" $fps
  run "$python" "$source_dir/tests/export_compare.py" colliders "$work/press.pvd"
  run "$python" "$source_dir/tests/export_compare.py" colliders "$work/cape.pvd"
else
  skipped+=("ParaView's series read by VTK: $python has no vtk or numpy (Debian python3-vtk9, python3-numpy)")
fi

if command -v node >/dev/null && [ -d "$source_dir/tests/js/node_modules/gltf-validator" ]; then
  run node "$source_dir/tests/js/validate_gltf.js" "$work/run.glb" "$work/press.glb" "$work/cape.glb"
else
  skipped+=("the Khronos glTF validator: no node, or no tests/js/node_modules (npm ci --prefix tests/js)")
fi

# Blender reads NAME.obj with its caches and NAME.glb at the frames given (tests/blender_roundtrip.py,
# into NAME-blender.json); its own output goes to a log, shown only when it fails.
blender_reads() {
  local name=$1
  shift
  if ! blender -b --factory-startup --python-exit-code 1 --python "$source_dir/tests/blender_roundtrip.py" -- \
      --obj "$work/$name.obj" --pc2 "$work/$name.pc2" --glb "$work/$name.glb" --fps $fps --frames "$@" \
      --out "$work/$name-blender.json" >"$work/$name-blender.log" 2>&1; then
    cat "$work/$name-blender.log"
    echo "export_roundtrip: FAILED: Blender did not read $name's exports" >&2
    exit 1
  fi
}

if command -v blender >/dev/null && "$python" -c "import vtk, numpy" 2>/dev/null; then
  blender_reads run $frames
  run "$python" "$source_dir/tests/export_compare.py" blender "$work/run.pvd" "$work/run-blender.json"
  for m in "${moving[@]}"; do
    read -r name _ frames <<<"$m"
    blender_reads "$name" $frames
  done
  run "$python" "$source_dir/tests/export_compare.py" blender "$work/press.pvd" "$work/press-blender.json" \
    --height "collider 0" 0 0 --height "collider 0" 54 -0.7
  run "$python" "$source_dir/tests/export_compare.py" blender "$work/cape.pvd" "$work/cape-blender.json"
else
  skipped+=("Blender's round trip: no blender (Debian blender) or no VTK to compare with")
fi

if [ ${#skipped[@]} -gt 0 ]; then
  for s in "${skipped[@]}"; do echo "export_roundtrip: SKIPPED $s; scripts/install-deps.sh installs it" >&2; done
  exit 77
fi
echo "export_roundtrip: every reader agrees"

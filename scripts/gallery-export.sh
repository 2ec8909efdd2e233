#!/usr/bin/env bash
# docs/export.md's "Blender beside springy": the bunny landing (scenes/bunny.toml at 1.6 s) drawn
# by springy (`springy frames`) and by Blender from springy's export (`springy export` to .glb,
# then scripts/blender_still.py: Cycles on the CPU), from the same camera, into docs/gallery.
# Needs a build in build/ and Debian's blender. About two minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
springy=./build/app/springy
work=$(mktemp -d /tmp/springy-gallery-export.XXXXXX)
trap 'rm -rf "$work"' EXIT
scene=scenes/bunny.toml
time=1.6     # [s]: the bunny squashed on the ground
fps=30
frame=48     # 1.6 s at 30 frames a second
camera=(0.0 3.5 18.0)
target=(0.0 2.0 0.0)
size=(960 540)
set_camera=(--set "render.camera.position=[${camera[0]}, ${camera[1]}, ${camera[2]}]"
            --set "render.camera.target=[${target[0]}, ${target[1]}, ${target[2]}]")

"$springy" frames "$scene" --times $time --width ${size[0]} --height ${size[1]} "${set_camera[@]}" -o "$work"
cp "$work"/*.png docs/gallery/export_bunny_springy.png
"$springy" export "$scene" --duration 2.0 --fps $fps -o "$work/bunny.glb" >/dev/null
blender -b --factory-startup --python-exit-code 1 --python scripts/blender_still.py -- "$work/bunny.glb" \
  --fps $fps --frame $frame --camera "${camera[@]}" --target "${target[@]}" --fov 60 --light 31.8 210 \
  --size "${size[@]}" --out "$work/blender.png" >"$work/blender.log" 2>&1 || { cat "$work/blender.log"; exit 1; }
cp "$work/blender.png" docs/gallery/export_bunny_blender.png
echo "docs/gallery/export_bunny_springy.png, docs/gallery/export_bunny_blender.png"

#!/usr/bin/env bash
# Regenerates the README's gallery: one contact sheet per showcase scene in docs/gallery/,
# four stills each at moments that tell the scene's story, the last at the scene's end; and for
# every scene the original project had, NAME_vs_original.png: the original's eight stills
# (/work/shared/seed/original-stills, or $SPRINGY_ORIGINAL_STILLS) above ours, eight evenly
# spaced from 0 to the scene's end, with the scene's camera (the original's). Needs a build
# (scripts/build.sh, which also builds tests/render/vs_original).
set -euo pipefail
cd "$(dirname "$0")/.."
springy=${SPRINGY_BUILD_DIR:-build}/app/springy
out=docs/gallery
mkdir -p "$out"
declare -A times=(
  [single_sphere]=0,1.9,2.6,12
  [spheres]=0,2.0,3.3,18
  [fixed_single_sphere]=0,1,3,12
  [ramp]=0,3.4,11.6,20
  [cube]=0,1.9,2.5,10
  [bunny]=0,1.5,2.3,25
  [bunny_light]=0,1.5,2.3,25
  [jelly]=0,1.45,1.8,12
  [sample]=0,2.3,4,40
  [head_on]=0,0.45,0.6,3
  [column]=0,0.8,1.6,5
  [pile]=0,0.8,2,8
  [stack]=0,0.6,1.5,12
  [drape]=0.3,0.5,1.2,5
  [flag]=1,4,16,20
  [press]=0,1.5,2.2,8
  [shaker]=0,1.1,2.3,6
  [cape]=0,1.25,4.3,7
)
for scene in "${!times[@]}"; do
  "$springy" frames "scenes/$scene.toml" -o "$out" --sheet-only --width 384 --height 216 \
    --times "${times[$scene]}" --duration "${times[$scene]##*,}" &
  # Two at a time: the machine has two cores.
  while [ "$(jobs -r | wc -l)" -ge 2 ]; do sleep 0.5; done
done
wait

originals=${SPRINGY_ORIGINAL_STILLS:-/work/shared/seed/original-stills}
vs=${SPRINGY_BUILD_DIR:-build}/tests/render/vs_original
if [ -d "$originals" ]; then
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  declare -A original=([bunny]=bunny [cube]=cube [fixed_single_sphere]=hangedSphere [jelly]=jelly
                       [single_sphere]=oneSphere [ramp]=ramp [spheres]=spheres)
  for scene in "${!original[@]}"; do
    duration=$(sed -n 's/^duration *= *\([0-9.]*\).*/\1/p' "scenes/$scene.toml" | head -1)
    times=$(awk -v d="$duration" 'BEGIN { for (i = 0; i < 8; i++) printf "%s%.2f", (i ? "," : ""), i * d / 7 }')
    (
      mkdir -p "$tmp/$scene"
      "$springy" frames "scenes/$scene.toml" -o "$tmp/$scene" --sheet-only --width 320 --height 180 --times "$times"
      "$vs" "$originals/${original[$scene]}.jpg" "$tmp/$scene/${scene}_sheet.png" "$out/${scene}_vs_original.png" \
        "original (Unity, 2022): ${original[$scene]}, 8 stills over its video" "springy: scenes/$scene.toml, 8 stills from 0 to $duration s"
    ) &
    while [ "$(jobs -r | wc -l)" -ge 2 ]; do sleep 0.5; done
  done
  wait
fi
ls -la "$out"

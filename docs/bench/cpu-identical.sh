#!/bin/bash
# A refactor's proof that nothing moved on the CPU: two furnace binaries (before and after) render
# the same scenes and settings on the CPU — the reference scenes, textured assets, every sampler,
# AOVs, adaptive sampling, Mitsuba's material model, both light-selection strategies — and each
# pair of images must be bit-identical (`furnace compare` RMSE 0 on the EXR, the same PNG bytes).
#
#   bash docs/bench/cpu-identical.sh OLD_BIN NEW_BIN [OUT_DIR]
#
# WIDTH, HEIGHT, SPP (160, 120, 32). Exits 1 when any pair differs or a render fails.
set -u
old=$1 new=$2 out=${3:-/tmp/cpu-identical}
root=$(cd "$(dirname "$0")/../.." && pwd)
R=$root/tests/data/references S=$root/tests/data/scenes
mkdir -p "$out"
cases=(
  "cbox-default|"
  "cbox-sobol-aovs|--sampler sobol --aovs --bounces 6"
  "cbox-pmj-mitsuba|--sampler pmj02 --masking separable --compensation off"
  "cbox-adaptive|--noise-threshold 0.05"
  "area|$R/lights/cbox_area.gltf"
  "area-power|$R/lights/cbox_area.gltf --light-selection power --triangle-sampling area"
  "many|$R/lights/cbox_many_lights.gltf"
  "point|$R/lights/cbox_point.gltf"
  "sundisc|$R/lights/cbox_sun_disc.gltf"
  "envmap|$R/envmap/envmap_spheres.gltf"
  "glass-box|$R/glass/glass_box.gltf --bounces 8"
  "glass-absorb|$R/glass/glass_absorb.gltf --bounces 8"
  "helmet|$S/DamagedHelmet/glTF-Binary/DamagedHelmet.glb"
  "boxtextured|$S/BoxTextured/glTF/BoxTextured.gltf"
  "cetra|$S/CornellBox-cetra/cornell_box.gltf"
)
fail=0
for c in "${cases[@]}"; do
  name=${c%%|*}; args=${c#*|}
  for side in old new; do
    bin=$old; [ $side = new ] && bin=$new
    # shellcheck disable=SC2086
    "$bin" render $args --backend cpu --width ${WIDTH:-160} --height ${HEIGHT:-120} --spp ${SPP:-32} --out "$out/$name-$side.exr" -q \
      > "$out/$name-$side.log" 2>&1 || { echo "$name: $side failed: $(tail -1 "$out/$name-$side.log")"; fail=1; }
  done
  rmse=$("$new" compare "$out/$name-new.exr" "$out/$name-old.exr" 2>&1 | awk '/^RMSE/ {print $2}')
  if [ "$rmse" = "0.000000e0" ] && cmp -s "$out/$name-new.png" "$out/$name-old.png"; then
    echo "$name: identical"
  else
    echo "$name: DIFFERENT (RMSE $rmse)"; fail=1
  fi
done
exit $fail

#!/bin/bash
# The point-light change against the binary before it (.dev/furnace-old.xz), one command: the
# films of both binaries with the defaults (320x240, 64 spp) on the box, the point-light box
# (`auto` gathers both of its lights, as before), the sun-disc box, the quad-light box, the
# 64-light box and the environment map, each against the other; then both binaries interleaved,
# ROUNDS (2) rounds, at 1920x1080 on the same scenes (random sampler). Needs .gl/,
# .dev/furnace-{new,old}.xz, .dev/sc/ (cbox.gltf/.bin).
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
xz -dc .dev/furnace-old.xz > /tmp/fold; chmod +x /tmp/fold
source docs/device/speed-env.sh
list=("" /tmp/sc/cbox_point.gltf /tmp/sc/cbox_sun_disc.gltf /tmp/sc/cbox_area.gltf /tmp/sc/cbox_many_lights.gltf /tmp/sc/envmap_spheres.gltf)
echo "== films, new against old (320x240, 64 spp, defaults)"
for sc in "${list[@]}"; do
  for b in old new; do /tmp/f$b render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/g$b.exr -q > /dev/null 2>&1; done
  echo "${sc:-cbox}: $(/tmp/fnew compare $W/gnew.exr $W/gold.exr | grep -E '^RMSE' | tr -s ' ')"
done
echo "== Msamples/s, 1920x1080, random sampler"
for round in $(seq ${ROUNDS:-2}); do
  for sc in "${list[@]}"; do for b in old new; do
    bench "$(basename "${sc:-cbox}") $b $round" f$b --scene ${sc:-cbox} --width 1920 --height 1080 --sampler random --min-seconds 1.5
  done; done
done

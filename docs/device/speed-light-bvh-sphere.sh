#!/bin/bash
# The light BVH's node records holding the bounding sphere and sin θo (formed once on the host)
# instead of the box's corners, against the binary before (.dev/furnace-old.xz): the two emitter
# boxes with the light BVH, interleaved, ROUNDS rounds (2), then the films against each other.
# Needs .gl/, .dev/furnace-{new,old}.xz, .dev/sc/; no Mitsuba.
for b in old new; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
source docs/device/speed-env.sh
for round in $(seq ${ROUNDS:-2}); do for n in 2 3; do sc=${scenes[$n]}; for b in old new; do
  bench "${sc%%|*} $b $round" f$b ${sc#*|} --sampler random --min-seconds 1.5
done; done; done
for sc in /tmp/sc/cbox_area.gltf /tmp/sc/cbox_many_lights.gltf; do
  for b in old new; do /tmp/f$b render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/g$b.exr -q > /dev/null 2>&1; done
  echo "$sc new against old: $(/tmp/fnew compare $W/gnew.exr $W/gold.exr | grep -E 'RMSE' | tr -s ' ')"
done

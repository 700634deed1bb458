#!/bin/bash
# A/B of the integrator's shadow rays queued and traced by the path loop's one trace call
# (binaries .dev/furnace-{old,BINS}.xz, old = before), interleaved, ROUNDS rounds (2), random sampler;
# the emitter scenes also with Mitsuba's light sampling; BINS at each --group-samples in GROUP_SAMPLES;
# then each film against old's.
BINS=${BINS:-new}
for b in old $BINS; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
source docs/device/speed-env.sh
for round in $(seq ${ROUNDS:-2}); do for sc in "${scenes[@]}"; do for b in old $BINS; do
  bench "${sc%%|*} $b $round" f$b ${sc#*|} --sampler random --min-seconds 1.5
done; done; done
for sc in "${scenes[2]}" "${scenes[3]}"; do for b in old $BINS; do
  bench "${sc%%|*} $b power+area" f$b ${sc#*|} --sampler random --min-seconds 1.5 --light-selection power --triangle-sampling area
done; done
for g in $GROUP_SAMPLES; do for sc in "${scenes[@]}"; do for b in $BINS; do
  bench "${sc%%|*} $b group $g" f$b ${sc#*|} --sampler random --min-seconds 1.5 --group-samples $g
done; done; done
for sc in "" /tmp/sc/cbox_area.gltf /tmp/sc/cbox_many_lights.gltf /tmp/sc/envmap_spheres.gltf $I; do
  for b in old $BINS; do /tmp/f$b render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/g$b.exr -q > /dev/null 2>&1; done
  for b in $BINS; do echo "${sc:-cbox} $b against old: $(/tmp/f$b compare $W/g$b.exr $W/gold.exr | grep RMSE)"; done
done

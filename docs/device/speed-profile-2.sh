#!/bin/bash
# Second profile run (same inputs as speed-profile.sh): invocations per pixel on every scene, the
# traversal stack's size and the trace counters' cost, equal-settings light sampling against
# Mitsuba, and the window-lit interior against Mitsuba.
# Measured with a2ecedf's kernel (a 32-entry stack, the default then) plus the environment
# overrides; with later binaries the FURNACE_TRV_STACK=32 runs are that kernel.
xz -dc .dev/furnace-new.xz > /tmp/fn; xz -dc .dev/pipeline-stats.xz > /tmp/ps; chmod +x /tmp/fn /tmp/ps
source docs/device/speed-env.sh
echo "== pipeline statistics: stack 16, no trace counters"
for e in "FURNACE_TRV_STACK=16" "FURNACE_TRV_STACK=32 FURNACE_NO_TRACE_COUNTERS=1" "FURNACE_TRV_STACK=16 FURNACE_NO_TRACE_COUNTERS=1"; do
  env $e /tmp/ps cbox 2>&1 | grep -E 'Register|Local|Shared|Binary' | sed "s|^|$e: |"
done
echo "== invocations per pixel (random sampler)"
for sc in "${scenes[@]}"; do for g in 1 2 4 8 16; do
  bench "${sc%%|*} group $g" fn ${sc#*|} --sampler random --min-seconds 1.5 --group-samples $g
done; done
echo "== stack 32/16, trace counters on/off (group 1 and the default)"
for sc in "${scenes[1]}" "${scenes[2]}" "${scenes[6]}"; do for g in 1 default; do
  ga="--group-samples $g"; [ $g = default ] && ga=""
  for e in "FURNACE_TRV_STACK=32" "FURNACE_TRV_STACK=16" "FURNACE_TRV_STACK=32 FURNACE_NO_TRACE_COUNTERS=1" "FURNACE_TRV_STACK=16 FURNACE_NO_TRACE_COUNTERS=1"; do
    env $e bash -c "$(declare -f bench); W=$W bench '${sc%%|*} $g $e' fn ${sc#*|} --sampler random --min-seconds 1.5 $ga"
  done
done; done
echo "== light sampling settings (1080p, random)"
for s in cbox_area cbox_many_lights; do
  for o in "" "--light-selection power" "--light-selection power --triangle-sampling area" "--light-sampling bsdf"; do
    bench "$s [$o]" fn --scene /tmp/sc/$s.gltf --width 1920 --height 1080 --sampler random --min-seconds 1.5 $o
  done
done
echo "== Mitsuba interior and lights, furnace beside"
for v in "interior_19880|1920x1440|$I|32|4|6" "interior_19880|1920x1080|$I|64|4|4" "cbox_area|1920x1080|/tmp/sc/cbox_area.gltf|64|4|4" "cbox_many_lights|1920x1080|/tmp/sc/cbox_many_lights.gltf|64|4|4"; do
  IFS='|' read -r s size path spp passes b <<< "$v"
  extra=""; [ $s = interior_19880 ] && [ $b = 4 ] && extra="--max-depth=5"
  ORACLE_SIZE=$size mi $s cuda_ad_rgb $spp $passes $extra
  python3 -c "import json; d=json.load(open('/tmp/mr/${s}_cuda_ad_rgb_$((spp*passes))spp.json')); print('mitsuba $s $size', round(d['Msamples_per_s'],1), 'render_s', round(d['render_s'],3))"
  for g in 1 default; do ga="--group-samples $g"; [ $g = default ] && ga=""
    bench "furnace $s $size group $g" fn --scene $path --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --spp $((spp*passes)) $ga
  done
  [ $s = interior_19880 ] || bench "furnace $s $size power+area" fn --scene $path --width ${size%x*} --height ${size#*x} --sampler random --spp $((spp*passes)) --light-selection power --triangle-sampling area
done
cp /tmp/mo/interior*.png $W/ 2>/dev/null
tar -czf $OUT/results.tgz -C $W . 2>/dev/null

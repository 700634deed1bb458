#!/bin/bash
# Before/after on the H200 (stack of 16, invocations per pixel by image size, balanced dispatch
# rows), interleaved, with Mitsuba 3 (cuda_ad_rgb) at equal samples in the same run. Inputs as
# speed-profile.sh, plus .dev/furnace-old.xz (the binary before).
for b in new old; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
source docs/device/speed-env.sh
echo "== old / new, random sampler, 2 rounds"
for round in 1 2; do for sc in "${scenes[@]}"; do for b in old new; do
  bench "${sc%%|*} $b $round" f$b ${sc#*|} --sampler random --min-seconds 1.5
done; done; done
echo "== new without loop bounding; new by invocations per pixel"
for sc in "${scenes[@]}"; do FURNACE_SHADER_CHECKS=noloop bench "${sc%%|*} new-noloop" fnew ${sc#*|} --sampler random --min-seconds 1.5; done
for sc in "${scenes[1]}" "${scenes[5]}" "${scenes[6]}"; do for g in 1 2 4 8; do
  bench "${sc%%|*} new group $g" fnew ${sc#*|} --sampler random --min-seconds 1.5 --group-samples $g
done; done
echo "== traversal counters (new, rays counted)"
for sc in "${scenes[@]}"; do
  /tmp/fnew bench --backend gpu ${sc#*|} --sampler random --min-seconds 1.5 -q --json $W/c.json > $W/c.log 2>&1 || tail -2 $W/c.log
  python3 -c "import json; d=json.load(open('$W/c.json')); print('${sc%%|*} counted', {k: d[k] for k in d if any(w in k for w in ('ray', 'node', 'triangle', 'stack', 'fallback', 'msamples'))})"
done
echo "== Mitsuba and furnace (new) at equal samples, random sampler"
for v in "${equal[@]}"; do
  IFS='|' read -r s size path spp passes b <<< "$v"
  mitsuba_at $s $size $spp $passes
  bench "furnace $s $size" fnew --scene $path --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --spp $((spp*passes))
  case $s in cbox_area|cbox_many_lights) bench "furnace $s $size power+area" fnew --scene $path --width ${size%x*} --height ${size#*x} --sampler random --spp $((spp*passes)) --light-selection power --triangle-sampling area;; esac
done
cp /tmp/mo/interior*.png /tmp/mo/*.json $W/ 2>/dev/null; cp /tmp/mr/*.json $W/ 2>/dev/null
tar -czf $OUT/results.tgz -C $W . 2>/dev/null

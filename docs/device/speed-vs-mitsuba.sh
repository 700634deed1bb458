#!/bin/bash
# furnace against Mitsuba 3 (cuda_ad_rgb) at equal samples on the seven speed configurations'
# scenes, in one device command: Mitsuba's Msamples/s (its render_s over 4 passes), furnace's
# (`furnace bench --spp` the same total, random sampler like Mitsuba's independent one) at the
# default workgroup size and at each size in GROUP_SIZES (FURNACE_GROUP_SIZE; default 256, the
# size before 1024 became the hardware default), and for the
# emitter scenes furnace with Mitsuba's light sampling (power-proportional choice, area sampling).
# Needs Mitsuba unpacked to /root/site (a first command carrying .mi), .gl/,
# .dev/furnace-new.xz, .dev/sc/{cbox,interior_19880}.*, .dev/oracle/.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
echo "== Mitsuba and furnace at equal samples, random sampler"
for v in "${equal[@]}"; do
  IFS='|' read -r s size path spp passes b <<< "$v"
  mitsuba_at $s $size $spp $passes
  args="--scene $path --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --spp $((spp*passes))"
  bench "furnace $s $size" fnew $args
  for g in ${GROUP_SIZES:-256}; do FURNACE_GROUP_SIZE=$g bench "furnace $s $size group $g" fnew $args; done
  case $s in cbox_area|cbox_many_lights) bench "furnace $s $size power+area" fnew $args --light-selection power --triangle-sampling area;; esac
done
echo "== the film does not depend on the workgroup size"
/tmp/fnew render --backend gpu --width 320 --height 240 --spp 64 --out $W/gdefault.exr -q > /dev/null 2>&1
for g in ${GROUP_SIZES:-256}; do
  FURNACE_GROUP_SIZE=$g /tmp/fnew render --backend gpu --width 320 --height 240 --spp 64 --out $W/g$g.exr -q > /dev/null 2>&1
  echo "group $g against the default: $(/tmp/fnew compare $W/g$g.exr $W/gdefault.exr | grep RMSE)"
done

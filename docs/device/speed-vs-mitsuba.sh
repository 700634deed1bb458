#!/bin/bash
# furnace against Mitsuba 3 (cuda_ad_rgb) at equal samples on the seven speed configurations'
# scenes, in one device command: Mitsuba's Msamples/s (its render_s over 4 passes), furnace's
# (`furnace bench --spp` the same total, random sampler like Mitsuba's independent one) with the
# defaults, with the profiling overrides in BEFORE (e.g. BEFORE=FURNACE_TRV_STACK=16: the shader
# before a change), at each workgroup size in GROUP_SIZES (FURNACE_GROUP_SIZE; none by default),
# with the binary .dev/furnace-old.xz when it travelled (the code before a change), and for the
# emitter scenes furnace with Mitsuba's light sampling (power-proportional choice, area
# sampling). ONLY (scene names of speed-env.sh's `equal`, e.g. "cbox cbox_area") runs a part, to
# stay within one device command. Then the film with BEFORE, at each size and of the old binary
# against the default's (FILMS=0 skips them).
# Needs Mitsuba unpacked to /root/site (a first command carrying .mi), .gl/,
# .dev/furnace-new.xz, .dev/sc/{cbox,interior_19880}.*, .dev/oracle/.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
if [ -f .dev/furnace-old.xz ]; then xz -dc .dev/furnace-old.xz > /tmp/fold; chmod +x /tmp/fold; fi
source docs/device/speed-env.sh
echo "== Mitsuba and furnace at equal samples, random sampler"
for v in "${equal[@]}"; do
  IFS='|' read -r s size path spp passes b <<< "$v"
  if [ -n "$ONLY" ] && [[ " $ONLY " != *" $s "* ]]; then continue; fi
  mitsuba_at $s $size $spp $passes
  args="--scene $path --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --spp $((spp*passes))"
  bench "furnace $s $size" fnew $args
  if [ -n "$BEFORE" ]; then (export $BEFORE; bench "furnace $s $size before ($BEFORE)" fnew $args); fi
  if [ -x /tmp/fold ]; then bench "furnace $s $size before (furnace-old)" fold $args; fi
  for g in $GROUP_SIZES; do FURNACE_GROUP_SIZE=$g bench "furnace $s $size group $g" fnew $args; done
  case $s in cbox_area|cbox_many_lights)
    bench "furnace $s $size power+area" fnew $args --light-selection power --triangle-sampling area
    if [ -x /tmp/fold ]; then bench "furnace $s $size power+area before (furnace-old)" fold $args --light-selection power --triangle-sampling area; fi;;
  esac
done
[ "$FILMS" = 0 ] && exit 0
echo "== the film with BEFORE, at each workgroup size and of the old binary against the default's"
for sc in "" /tmp/sc/cbox_area.gltf /tmp/sc/cbox_many_lights.gltf /tmp/sc/envmap_spheres.gltf $I; do
  /tmp/fnew render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/gdefault.exr -q > /dev/null 2>&1
  if [ -n "$BEFORE" ]; then
    env $BEFORE /tmp/fnew render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/gbefore.exr -q > /dev/null 2>&1
    echo "${sc:-cbox} before ($BEFORE) against the default: $(/tmp/fnew compare $W/gbefore.exr $W/gdefault.exr | grep RMSE)"
  fi
  for g in $GROUP_SIZES; do
    FURNACE_GROUP_SIZE=$g /tmp/fnew render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/g$g.exr -q > /dev/null 2>&1
    echo "${sc:-cbox} group $g against the default: $(/tmp/fnew compare $W/g$g.exr $W/gdefault.exr | grep RMSE)"
  done
  if [ -x /tmp/fold ]; then
    /tmp/fold render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/gold.exr -q > /dev/null 2>&1
    echo "${sc:-cbox} furnace-old against the default: $(/tmp/fnew compare $W/gold.exr $W/gdefault.exr | grep RMSE)"
    for o in "--light-selection power --triangle-sampling area" "--light-selection power" "--triangle-sampling area"; do
      case $sc in *cbox_area*|*many_lights*)
        /tmp/fold render $sc $o --backend gpu --width 320 --height 240 --spp 64 --out $W/gold.exr -q > /dev/null 2>&1
        /tmp/fnew render $sc $o --backend gpu --width 320 --height 240 --spp 64 --out $W/gnew.exr -q > /dev/null 2>&1
        echo "${sc:-cbox} $o: furnace-old against new: $(/tmp/fnew compare $W/gold.exr $W/gnew.exr | grep RMSE)";;
      esac
    done
  fi
done

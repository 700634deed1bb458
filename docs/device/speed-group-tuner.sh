#!/bin/bash
# Invocations per pixel chosen by timing (GroupTuner) against the image-size rule alone
# (.dev/furnace-old.xz): Mitsuba and both binaries at equal samples on the interior (Mitsuba
# unpacked to /root/site by a first command carrying .mi), then the two binaries interleaved on
# every configuration of speed-env.sh and the interior at 8 bounces, and the films against each
# other. Needs .gl/, .dev/furnace-{new,old}.xz, .dev/sc/, .dev/oracle/.
ONLY=interior_19880 FILMS=0 bash docs/device/speed-vs-mitsuba.sh
source docs/device/speed-env.sh
scenes+=("int1440b8|--scene $I --width 1920 --height 1440 --bounces 8")
for sc in "${scenes[@]}"; do for b in old new; do
  bench "${sc%%|*} $b" f$b ${sc#*|} --sampler random --min-seconds 1.5
done; done
for sc in $I ""; do
  for b in old new; do /tmp/f$b render $sc --backend gpu --width 1920 --height 1440 --spp 24 --out $W/g$b.exr -q > /dev/null 2>&1; done
  echo "${sc:-cbox} new against old: $(/tmp/fnew compare $W/gnew.exr $W/gold.exr | grep -E 'RMSE' | tr -s ' ')"
done

#!/bin/bash
# The point lights' shadow rays queued (a slot each, up to MAX_QUEUED_POINT_LIGHTS) against
# traced where they are gathered (.dev/furnace-old.xz): Mitsuba and both binaries at equal samples
# on cbox_point (Mitsuba unpacked to /root/site by a first command carrying .mi), then the two
# binaries interleaved, ROUNDS rounds (2), on the point-light box and three scenes without point
# lights (which must not move), and the films against each other. Needs .gl/,
# .dev/furnace-{new,old}.xz, .dev/sc/, .dev/oracle/.
ONLY=cbox_point FILMS=0 bash docs/device/speed-vs-mitsuba.sh
source docs/device/speed-env.sh
for round in $(seq ${ROUNDS:-2}); do
  for n in 7 8 1 2; do sc=${scenes[$n]}; for b in old new; do
    bench "${sc%%|*} $b $round" f$b ${sc#*|} --sampler random --min-seconds 1.5
  done; done
done
for sc in /tmp/sc/cbox_point.gltf /tmp/sc/cbox_sun_disc.gltf ""; do
  for b in old new; do /tmp/f$b render $sc --backend gpu --width 320 --height 240 --spp 64 --out $W/g$b.exr -q > /dev/null 2>&1; done
  echo "${sc:-cbox} new against old: $(/tmp/fnew compare $W/gnew.exr $W/gold.exr | grep -E 'RMSE|ratio' | tr -s ' ' | tr '\n' ' ')"
done

#!/bin/bash
# Kernel variants on one binary, no rebuild: the driver's statistics (pipeline_stats, STATS=1)
# and the speed of the default kernel against wgpu's loop counters (checked; noloop is the
# default since this script's first run), and FURNACE_SHADER_EDIT variants from
# docs/device/edits/ (EDITS, names without .txt), on the configurations of speed-env.sh (ONLY:
# their names, default all) and the emitter scenes with Mitsuba's light sampling (power
# choice, area sampling; area-compiled.txt there when the binary predates the compiled choice).
# Each configuration: the default once to settle the clocks, the variants, the default again.
# Needs .gl/, .dev/s6/{furnace-cur,pipeline-stats}.xz, .dev/sc/.
xz -dc .dev/s6/furnace-cur.xz > /tmp/fcur; chmod +x /tmp/fcur
xz -dc .dev/s6/pipeline-stats.xz > /tmp/ps; chmod +x /tmp/ps
source docs/device/speed-env.sh
E=$PWD/docs/device/edits
EDITS=${EDITS:-trv-one-item}
MIN_S=${MIN_S:-1}
scenes+=("area1080pa|--scene /tmp/sc/cbox_area.gltf --width 1920 --height 1080 --light-selection power --triangle-sampling area"
         "many1080pa|--scene /tmp/sc/cbox_many_lights.gltf --width 1920 --height 1080 --light-selection power --triangle-sampling area")
if [ -n "$STATS" ]; then
  echo "== driver statistics"
  for s in cbox /tmp/sc/cbox_area.gltf /tmp/sc/cbox_many_lights.gltf /tmp/sc/envmap_spheres.gltf; do
    /tmp/ps $s 2>&1 | grep -v "^scene\|^device"
    /tmp/ps $s --checks checked 2>&1 | grep -v "^scene\|^device"
    /tmp/ps $s --counters 2>&1 | grep -v "^scene\|^device"
    for e in $EDITS; do FURNACE_SHADER_EDIT=$E/$e.txt /tmp/ps $s 2>&1 | grep -v "^scene\|^device"; done
  done
fi
for sc in "${scenes[@]}"; do
  name=${sc%%|*}; args=${sc#*|}
  if [ -n "$ONLY" ] && [[ " $ONLY " != *" $name "* ]]; then continue; fi
  echo "== $name"
  bench "$name warm-up" fcur $args --sampler random --min-seconds $MIN_S
  bench "$name default" fcur $args --sampler random --min-seconds $MIN_S
  FURNACE_SHADER_CHECKS=checked bench "$name checked" fcur $args --sampler random --min-seconds $MIN_S
  for e in $EDITS; do
    FURNACE_SHADER_EDIT=$E/$e.txt bench "$name $e" fcur $args --sampler random --min-seconds $MIN_S
  done
  bench "$name default again" fcur $args --sampler random --min-seconds $MIN_S
done

#!/bin/bash
# At the 1024-invocation workgroups (64 registers), does the loop shape or the grouping want
# retuning? The default kernel against the same without wgpu's loop counters
# (FURNACE_SHADER_CHECKS=noloop: the driver unrolls the node test's loop), interleaved, on the
# six speed scenes; then invocations per pixel (--group-samples) on the 1080p box and the
# 1440p interior. Needs .gl/, .dev/furnace-new.xz, .dev/sc/; no Mitsuba.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
echo "== default / noloop, random sampler"
for sc in "${scenes[@]}"; do
  name=${sc%%|*}; [ "$name" = int1080b4 ] && continue
  bench "$name default" fnew ${sc#*|} --sampler random --min-seconds 1
  FURNACE_SHADER_CHECKS=noloop bench "$name noloop" fnew ${sc#*|} --sampler random --min-seconds 1
done
echo "== invocations per pixel"
for sc in "${scenes[1]}" "${scenes[6]}"; do for g in 1 2 4 8; do
  bench "${sc%%|*} group-samples $g" fnew ${sc#*|} --sampler random --min-seconds 1 --group-samples $g
done; done

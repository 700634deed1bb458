#!/bin/bash
# The light BVH's parts on the emitter scenes, timed by leaving them out (FURNACE_SHADER_EDIT
# with docs/device/edits/light-bvh-*.txt: the importance without its cone bounds, the pmf walk
# on emission hits, both), against the default and power choice, and the kernel without
# wgpu's runtime checks; two rounds. Needs .gl/, .dev/furnace-new.xz, .dev/sc/; no Mitsuba.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
E=$PWD/docs/device/edits
r="--sampler random --min-seconds 1"
for round in 1 2; do for i in 2 3; do sc=${scenes[$i]}; n=${sc%%|*}; a=${sc#*|}
  bench "$n default" fnew $a $r
  bench "$n power" fnew $a $r --light-selection power
  for x in light-bvh-no-cone light-bvh-no-pmf light-bvh-no-cone-no-pmf; do FURNACE_SHADER_EDIT=$E/$x.txt bench "$n $x" fnew $a $r; done
  FURNACE_SHADER_CHECKS=unchecked bench "$n unchecked" fnew $a $r
done; done

#!/bin/bash
# The traversal stack sized by the tree's depth (the default) against the fixed 16 it had
# (FURNACE_TRV_STACK=16), twice, interleaved, on the seven speed configurations; then, at the
# default stack, the emitter scenes' parts timed by leaving them out (FURNACE_SHADER_EDIT with
# docs/device/edits/*.txt: the MIS weight of emission reached by BSDF samples, the emitter
# samples' shadow rays, the emitter samples altogether), Mitsuba's light sampling (power choice,
# area sampling) and the kernel without loop counters; workgroups of 512 and 768; invocations
# per pixel on the 1080p box and the 1440p interior. Needs .gl/, .dev/furnace-new.xz, .dev/sc/;
# no Mitsuba.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
E=$PWD/docs/device/edits
r="--sampler random --min-seconds 1"
echo "== stack by depth against 16, twice"
for round in 1 2; do for sc in "${scenes[@]}"; do n=${sc%%|*}; a=${sc#*|}
  bench "$n depth" fnew $a $r
  python3 -c "import json; d=json.load(open('$W/b.json')); print('   stack', d['gpu_traversal_stack'], 'group size', d['gpu_group_size'])"
  FURNACE_TRV_STACK=16 bench "$n stack16" fnew $a $r
done; done
echo "== emitter scenes: parts left out"
for i in 2 3; do sc=${scenes[$i]}; n=${sc%%|*}; a=${sc#*|}
  bench "$n default" fnew $a $r
  bench "$n power+area" fnew $a $r --light-selection power --triangle-sampling area
  for x in no-emission-mis no-emitter-shadow no-emitter-samples; do FURNACE_SHADER_EDIT=$E/$x.txt bench "$n $x" fnew $a $r; done
  FURNACE_SHADER_CHECKS=noloop bench "$n noloop" fnew $a $r
done
echo "== workgroup sizes"
for i in 1 2 3 4 6; do sc=${scenes[$i]}; n=${sc%%|*}; a=${sc#*|}
  for g in 512 768; do FURNACE_GROUP_SIZE=$g bench "$n group $g" fnew $a $r; done
done
echo "== invocations per pixel"
for g in 2 8; do bench "cbox1080 group-samples $g" fnew ${scenes[1]#*|} $r --group-samples $g; done
for g in 1 4; do bench "int1440b6 group-samples $g" fnew ${scenes[6]#*|} $r --group-samples $g; done

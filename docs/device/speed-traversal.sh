#!/bin/bash
# The traversal's node test and loads, interleaved on the H200: `old` (a loop over the eight
# child slots, the node and triangle structs read field by field), `a` (the eight slots written
# out), `b` (a + nodes and triangles read as 16-byte words), each with wgpu's loop counters
# (the hardware default) and, for a and b, without; then the driver's statistics of b.
# Binaries (release, stripped, xz): old = 93a9269 (the looped test), b = 7ac2548, a = 7ac2548
# with `trv_node(..)` / `trv_triangle(..)` read back as `bvh_nodes[..]` / `bvh_triangles[..]`
# (structs again in `binding_list`). Needs .gl/, .dev/furnace-{old,a,b}.xz,
# .dev/pipeline-stats.xz (built from b) and .dev/sc/{cbox,interior_19880}.* (make_interior.py
# .dev/sc 2e4).
for b in ${BINS:-old a b}; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
[ -n "$QUICK" ] || { xz -dc .dev/pipeline-stats.xz > /tmp/ps; chmod +x /tmp/ps; }
source docs/device/speed-env.sh
# ONLY="name ...": those scenes alone; ROUNDS (2), BINS ("old a b"), MIN_S (1.5); QUICK=1 skips
# the noloop runs and the statistics (a short device budget).
echo "== ${BINS:-old a b}, random sampler, ${ROUNDS:-2} rounds"
for round in $(seq ${ROUNDS:-2}); do for sc in "${scenes[@]}"; do
  if [ -n "$ONLY" ] && [[ " $ONLY " != *" ${sc%%|*} "* ]]; then continue; fi
  for b in ${BINS:-old a b}; do
    bench "${sc%%|*} $b $round" f$b ${sc#*|} --sampler random --min-seconds ${MIN_S:-1.5}
done; done; done
[ -n "$QUICK" ] && exit 0
echo "== a / b without loop counters"
for sc in "${scenes[1]}" "${scenes[2]}" "${scenes[6]}"; do for b in a b; do
  FURNACE_SHADER_CHECKS=noloop bench "${sc%%|*} $b-noloop" f$b ${sc#*|} --sampler random --min-seconds ${MIN_S:-1.5}
done; done
echo "== pipeline statistics of b"
for s in cbox /tmp/sc/cbox_area.gltf $I; do for c in checked noloop; do
  /tmp/ps $s --checks $c 2>&1 | grep -v '^device' | sed "s|^|$(basename $s) $c: |"
done; done

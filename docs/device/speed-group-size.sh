#!/bin/bash
# One shadow-ray call site for every light kind (`new`, not kept) against the kernel before it (`head`,
# da84d86), and `new` in workgroups of 1024 invocations (FURNACE_GROUP_SIZE: the driver must fit
# 1024 invocations in one multiprocessor, at most 64 registers each), interleaved on the H200;
# then the driver's statistics by workgroup size. Needs .gl/, .dev/furnace-{head,new}.xz,
# .dev/pipeline-stats.xz (built from new) and .dev/sc/{cbox,interior_19880}.*; no Mitsuba.
# ROUNDS (2), MIN_S (1), BINS ("head new new1024": new1024 is new with FURNACE_GROUP_SIZE=1024),
# ONLY="name ..." as in speed-traversal.sh.
for b in head new; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
xz -dc .dev/pipeline-stats.xz > /tmp/ps; chmod +x /tmp/ps
source docs/device/speed-env.sh
echo "== driver statistics of new by workgroup size"
for s in cbox /tmp/sc/cbox_many_lights.gltf; do for g in ${GROUPS_PS:-256 1024}; do
  FURNACE_GROUP_SIZE=$g timeout 60 /tmp/ps $s 2>&1 | grep -v '^device' | sed "s|^|$(basename $s) $g: |"
done; done
echo "== ${BINS:-head new new1024}, random sampler, ${ROUNDS:-2} rounds"
for round in $(seq ${ROUNDS:-2}); do for sc in "${scenes[@]}"; do
  name=${sc%%|*}
  [ "$name" = int1080b4 ] && continue
  if [ -n "$ONLY" ] && [[ " $ONLY " != *" $name "* ]]; then continue; fi
  for b in ${BINS:-head new new1024}; do
    g=${b#new}; bin=f${b%1024}; bin=${bin%512}
    if [ -n "$g" ] && [ "$g" != "$b" ]; then
      FURNACE_GROUP_SIZE=$g bench "$name $b $round" $bin ${sc#*|} --sampler random --min-seconds ${MIN_S:-1}
    else
      bench "$name $b $round" $bin ${sc#*|} --sampler random --min-seconds ${MIN_S:-1}
    fi
done; done; done

#!/bin/bash
# Traversal counts of the two trees on the H200 (the roofline's inputs): rays per sample, nodes
# and triangles per ray, counted by `furnace bench`'s counting kernel, for the binary of
# 123afc7 (.dev/furnace-new.xz, serial `Slow`) and the head (.dev/furnace-vs.xz, parallel
# `VerySlow`). Inputs as speed-ab.sh.
for b in new vs; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
source docs/device/speed-env.sh
for sc in "${scenes[1]}" "${scenes[3]}" "${scenes[5]}" "${scenes[6]}"; do for b in new vs; do
  /tmp/f$b bench --backend gpu ${sc#*|} --sampler random --min-seconds 1.5 -q --json $W/c.json > $W/c.log 2>&1 || tail -2 $W/c.log
  python3 -c "import json; d=json.load(open('$W/c.json')); print('${sc%%|*} $b', {k: (round(v, 3) if isinstance(v, float) else v) for k, v in d.items() if any(w in k for w in ('ray', 'node', 'triangle', 'msamples', 'bvh_bytes'))})"
done; done

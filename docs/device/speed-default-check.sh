#!/bin/bash
# The defaults as shipped (workgroups of 1024; no loop counters for kernels that sample no
# lights), one bench per scene class: the box at 256² and 1080p, the quad-light box, the 1440p
# interior. A short confirmation run. Needs .gl/, .dev/furnace-new.xz, .dev/sc/.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
for i in 0 1 2 6; do sc=${scenes[$i]}; bench "${sc%%|*} shipped" fnew ${sc#*|} --sampler random --min-seconds 1; done

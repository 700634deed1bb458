#!/bin/bash
# Emitter scenes at 1920x1080: the previous binary (bin and coin as two draws) against this one
# (one pair), interleaved; images must be identical.
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-new.xz > /tmp/fn; xz -dc .dev/furnace-prev.xz > /tmp/fp; chmod +x /tmp/fn /tmp/fp
R=tests/data/references/lights
for round in 1 2 3; do for s in cbox_area cbox_many_lights; do for smp in sobol random; do for b in fp fn; do
  /tmp/$b bench --backend gpu --scene $R/$s.gltf --width 1920 --height 1080 --sampler $smp --spp 256 --no-rays -q --json /tmp/b.json > /dev/null 2>&1
  python3 -c "import json; d=json.load(open('/tmp/b.json')); print('$b $s $smp $round', round(d['msamples_per_s'],1))"
done; done; done; done
for b in fp fn; do /tmp/$b render $R/cbox_many_lights.gltf --spp 64 --width 256 --backend gpu --out /tmp/img_$b -q; done
/tmp/fn compare /tmp/img_fn.exr /tmp/img_fp.exr | sed -n 3,5p

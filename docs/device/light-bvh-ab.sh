#!/bin/bash
# Two furnace binaries interleaved on the emitter scenes at 1920x1080, 256 spp (Sobol, and
# random on the 64 emitters), light BVH and power: .dev/furnace-old.xz against
# .dev/furnace-new.xz (the light-BVH layout change being measured); the 256-spp images of the
# two are compared (the same paths: RMSE 0 expected).
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-old.xz > /tmp/fo; xz -dc .dev/furnace-new.xz > /tmp/fn; chmod +x /tmp/fo /tmp/fn
R=$PWD/tests/data/references/lights; S=$PWD/tests/data/scenes; W=/tmp/res; mkdir -p $W
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
bench() { # binary, scene, sampler, selection, tag
  $1 bench --backend gpu --scene $2 --width 1920 --height 1080 --sampler $3 --light-selection $4 --spp 256 --no-rays -q --json $W/b.json > /dev/null 2>&1
  python3 -c "import json; d=json.load(open('$W/b.json')); print('$5', round(d['msamples_per_s'],1))"
}
for round in 1 2 3; do
  for sc in $R/cbox_many_lights.gltf $S/CornellBox-cetra/cornell_box.gltf $S/DamagedHelmet/glTF-Binary/DamagedHelmet.glb; do
    n=$(basename $sc | cut -d. -f1)
    for smp in sobol random; do
      [ $smp = random ] && [ $n != cbox_many_lights ] && continue
      for b in fo fn; do bench /tmp/$b $sc $smp bvh "$round $n $smp bvh $b"; done
      bench /tmp/fn $sc $smp power "$round $n $smp power fn"
    done
  done
done
for b in fo fn; do /tmp/$b render $R/cbox_many_lights.gltf --spp 256 --width 256 --backend gpu --out $W/img_$b -q; done
/tmp/fn compare $W/img_fo.exr $W/img_fn.exr | sed -n 1,3p

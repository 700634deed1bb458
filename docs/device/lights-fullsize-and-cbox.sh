#!/bin/bash
# furnace only: full-size GPU renders of the light references, cbox before/after, emitter benches.
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-new.xz > /tmp/fn; xz -dc .dev/furnace-old.xz > /tmp/fo; chmod +x /tmp/fn /tmp/fo
R=tests/data/references/lights
python3 -c "import numpy; print('numpy', numpy.__version__)" 2>&1 | head -1
python3 --version
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
echo "== full size 256^2, 65536 spp, GPU, Mitsuba model, Sobol"
for s in cbox_area cbox_many_lights cbox_sun_disc cbox_point; do
  /usr/bin/time -f "$s render wall %e s" /tmp/fn render $R/$s.gltf --spp 65536 --width 256 --masking separable --compensation off --backend gpu --out $OUT/$s -q
  /tmp/fn compare $OUT/$s.exr $R/${s}_ref_bounces4.exr --stderr $R/${s}_ref_bounces4_stderr.exr | sed -n 3,9p
done
echo "== cbox 1920x1080 old/new interleaved (no emitters: must cost nothing)"
for round in 1 2 3; do for smp in random sobol; do for b in fo fn; do
  /tmp/$b bench --backend gpu --scene cbox --width 1920 --height 1080 --sampler $smp --min-seconds 3 --no-rays -q --json $OUT/cbox_${b}_${smp}_$round.json > /dev/null 2>&1
  python3 -c "import json,sys; d=json.load(open('$OUT/cbox_${b}_${smp}_$round.json')); print('$b $smp $round', d['msamples_per_s'], d['spp'], d['gpu_scene_bytes'])" 2>&1 | head -2
done; done; done
echo "== light scenes 1920x1080, each light sampling"
for s in cbox_area cbox_many_lights cbox_sun_disc; do for ls in mis nee bsdf; do
  /tmp/fn bench --backend gpu --scene $R/$s.gltf --width 1920 --height 1080 --light-sampling $ls --min-seconds 3 --no-rays -q --json $OUT/bench_${s}_$ls.json > /dev/null 2>&1 || echo "bench failed $s $ls"; python3 -c "import json; d=json.load(open('$OUT/bench_${s}_$ls.json')); print('$s $ls', d.get('msamples_per_s'), d.get('gpu_bytes_per_triangle'), d.get('gpu_scene_bytes'), d.get('spp'))"
done; done
ls $OUT

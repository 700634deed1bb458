#!/bin/bash
# Environment maps on the H200, without Mitsuba: the GPU against Mitsuba's environment-map
# reference (tests/mitsuba.rs's ignored GPU test, run on hardware), the full-size image means, a
# scene without a map against the previous binary (it must pay nothing), and an 8192x4096 map's
# time to first frame and peak memory. Needs .dev/furnace-new.xz, .dev/furnace-old.xz and
# .dev/mitsuba-test.xz (the stripped furnace-tests `all` test binary, test profile, whose `mitsuba` module is `tests/mitsuba.rs`).
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
for b in new old; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
xz -dc .dev/mitsuba-test.xz > /tmp/mt; chmod +x /tmp/mt
W=/tmp/res; mkdir -p $W
save() { tar -czf $OUT/results.tgz -C $W .; }  # after each section: a timeout keeps what is done
peak() { python3 -c "import resource, subprocess, sys; subprocess.run(sys.argv[1:]); print('peak RSS', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss // 1024, 'MiB')" "$@"; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
E=$PWD/tests/data/references/envmap
echo "== the GPU against Mitsuba's envmap reference (20x15 of 16x16 blocks, 512 passes x 64 spp)"
# The test binary finds tests/data beside the crate it was built from.
[ "$PWD" = /work/main ] || { mkdir -p /work/main && ln -sfn $PWD/tests /work/main/tests; }
(cd /work/main/tests && /tmp/mt --ignored --exact mitsuba::environment_map_matches_mitsuba_gpu --nocapture 2>&1 | grep -v XDG | grep -E '^\||test result|panicked' )
echo "== full size 320x240, 65536 spp, GPU, Mitsuba's model: image mean against the reference"
for es in importance compensated; do
  /tmp/fnew render $E/envmap_spheres.gltf --spp 65536 --width 320 --masking separable --compensation off --backend gpu --env-sampling $es --out $W/full_$es -q
  echo "env sampling $es"; /tmp/fnew compare $W/full_$es.exr $E/envmap_spheres_ref_bounces4.exr | sed -n 3,5p
done
rm -f $W/full_*
save
echo "== scenes without a map, 1920x1080, 256 spp: the previous binary (bf0c2c1) and this one interleaved"
L=$PWD/tests/data/references/lights
for round in 1 2 3; do for s in cbox $L/cbox_area.gltf $L/cbox_sun_disc.gltf; do for b in old new; do
  if [ $s = cbox ]; then sc=""; else sc="--scene $s"; fi
  /tmp/f$b bench --backend gpu $sc --width 1920 --height 1080 --spp 256 --no-rays -q --json $W/nomap.json > /dev/null 2>&1
  python3 -c "import json; d=json.load(open('$W/nomap.json')); print('$b', '$(basename $s)', $round, round(d['msamples_per_s'],1), 'Msamples/s')"
done; done; done
save
echo "== 8192x4096 map: time to first frame and peak memory (and the scene's own 512x256 for comparison)"
python3 docs/device/make_env_maps.py sky /tmp/big.hdr 8192 4096
ls -la /tmp/big.hdr
for be in gpu cpu; do
  for env in own big; do
    if [ $env = big ]; then ea="--env /tmp/big.hdr"; else ea=""; fi
    peak /tmp/fnew bench --backend $be --scene $E/envmap_spheres.gltf $ea --width 320 --height 240 --spp 4 --no-rays -q --json $W/env_$be.json 2>&1 | grep -v '^$' | tail -2
    python3 -c "import json; d=json.load(open('$W/env_$be.json')); print('$be $env: time to first frame', round(d['time_to_first_frame_s'],2), 's; GPU scene bytes', d.get('gpu_scene_bytes'))"
  done
done
save
ls -la $OUT

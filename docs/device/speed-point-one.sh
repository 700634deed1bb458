#!/bin/bash
# One point light per event (`--point-lights one`, chosen by power) against a shadow ray to each
# (`all`, the default) and against Mitsuba 3 (cuda_ad_rgb, one emitter per event), one command:
#  1. samples/s at equal samples (the `equal` configuration of cbox_point, 1920x1080, 64 x 4
#     spp; random sampler), Mitsuba first, then ROUNDS (2) interleaved rounds of both
#     strategies, at 1080p and 256²;
#  2. the same on a box with 32 point lights (cbox_point's two and 30 dim ones under the
#     ceiling, make_point_box.py), where `all` traces 32 shadow rays per event and `one` one;
#  3. error per sample: RMSE against the 256² reference after 64, 256 and 1024 spp for both
#     strategies (Owen-Sobol, the default, and random) and for Mitsuba; with the 256² rates of
#     step 1 that gives the seconds each needs for an error (furnace: spp·pixels / rate,
#     steady state; Mitsuba: its render_s, as speed-equal-time.sh quotes it).
# Needs .gl/, .dev/furnace-new.xz, .dev/sc/ (cbox.gltf/.bin), .dev/oracle/, and Mitsuba
# unpacked to /root/site by a first command carrying .mi (speed-env.sh).
xz -dc .dev/furnace-new.xz > /tmp/fn; chmod +x /tmp/fn
source docs/device/speed-env.sh
python3 docs/device/make_point_box.py 32 /tmp/sc/cbox_point.gltf /tmp/sc/cbox_point32.gltf
echo "== 1, 2: Msamples/s at equal samples (random sampler)"
mitsuba_at cbox_point 1920x1080 64 4
mitsuba_at cbox_point32 1920x1080 64 4
for round in $(seq ${ROUNDS:-2}); do
  for s in cbox_point cbox_point32; do for size in "1920 1080" "256 256"; do for p in all one; do
    set -- $size
    bench "$s ${1}x$2 $p $round" fn --scene /tmp/sc/$s.gltf --width $1 --height $2 --sampler random --point-lights $p --min-seconds 1.5
  done; done; done
done
echo "== 3: RMSE against the 256² reference"
ref=$R/lights/cbox_point_ref_bounces4.exr
for spp in 64 256 1024; do
  ORACLE_SIZE=256x256 mi cbox_point cuda_ad_rgb $spp 1
  t=$(python3 -c "import json; print(round(json.load(open('/tmp/mr/cbox_point_cuda_ad_rgb_${spp}spp.json'))['render_s'], 4))")
  echo "mitsuba $spp spp render_s $t $(/tmp/fn compare /tmp/mo/cbox_point_cuda_ad_rgb_${spp}spp.exr $ref | grep -E '^RMSE' | tr -s ' ')"
  for sampler in sobol random; do for p in all one; do
    /tmp/fn render /tmp/sc/cbox_point.gltf --backend gpu --width 256 --height 256 --masking separable --compensation off \
      --sampler $sampler --point-lights $p --spp $spp --out $W/p.exr -q > /dev/null 2>&1
    echo "furnace $sampler $p $spp spp $(/tmp/fn compare $W/p.exr $ref | grep -E '^RMSE' | tr -s ' ')"
  done; done
done

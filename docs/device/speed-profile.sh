#!/bin/bash
# Where the megakernel's time goes, and furnace against Mitsuba 3 (cuda_ad_rgb) in one run:
# 1. the driver's statistics of the integrator pipeline per scene, with wgpu's runtime checks and
#    without (`pipeline_stats` example: registers, spills, instructions);
# 2. the same binary with the shader's runtime checks on, without loop bounding, without integer
#    division guards, and unchecked (FURNACE_SHADER_CHECKS), interleaved, on every scene;
# 3. invocations per pixel on the 1920x1440 interior; bounces 0..6 there (GPU timestamps);
# 4. Mitsuba and furnace interleaved at equal samples on every scene.
# Measured with a2ecedf's kernel (a 32-entry traversal stack, 16 invocations per pixel capped by
# the pass's samples); later binaries get that stack back with FURNACE_TRV_STACK=32 below.
export FURNACE_TRV_STACK=32
# Needs .gl/, .dev/furnace-new.xz, .dev/pipeline-stats.xz, .dev/oracle/, .mi/mitsuba-cuda.tar.xz and
# .dev/sc/interior_19880.gltf (make_interior.py .dev/sc 2e4).
xz -dc .dev/furnace-new.xz > /tmp/fn; xz -dc .dev/pipeline-stats.xz > /tmp/ps; chmod +x /tmp/fn /tmp/ps
source docs/device/speed-env.sh

echo "== 1. pipeline statistics"
for s in cbox /tmp/sc/cbox_area.gltf /tmp/sc/envmap_spheres.gltf $I; do for c in checked unchecked; do
  /tmp/ps $s --checks $c 2>&1 | grep -v '^device' | sed "s|^|$(basename $s) $c: |"
done; done

# This run's five configurations (the interior by its 1440p name).
scenes=("cbox256|--scene cbox --width 256 --height 256"
        "cbox1080|--scene cbox --width 1920 --height 1080"
        "area1080|--scene /tmp/sc/cbox_area.gltf --width 1920 --height 1080"
        "env1080|--scene /tmp/sc/envmap_spheres.gltf --width 1920 --height 1080"
        "interior1440|--scene $I --width 1920 --height 1440 --bounces 6")
echo "== 2. runtime checks, random sampler, 2 rounds"
for round in 1 2; do for sc in "${scenes[@]}"; do for c in checked noloop unchecked; do
  FURNACE_SHADER_CHECKS=$c bench "${sc%%|*} $c $round" fn ${sc#*|} --sampler random --min-seconds 2
done; done; done

echo "== 3. interior 1920x1440: invocations per pixel; bounces"
for g in 1 2 4 8 16 32; do bench "interior1440 group $g" fn --scene $I --width 1920 --height 1440 --bounces 6 --sampler random --min-seconds 2 --group-samples $g; done
for b in 0 1 2 3 4 5 6; do bench "interior1440 bounces $b" fn --scene $I --width 1920 --height 1440 --bounces $b --sampler random --min-seconds 2; done

echo "== 4. Mitsuba and furnace at equal samples (random sampler), 2 rounds"
for round in 1; do
  for v in "cbox|256x256|cbox|64|4" "cbox|1920x1080|cbox|64|4" "cbox_area|1920x1080|/tmp/sc/cbox_area.gltf|64|4" \
           "cbox_many_lights|1920x1080|/tmp/sc/cbox_many_lights.gltf|64|4" "envmap_spheres|1920x1080|/tmp/sc/envmap_spheres.gltf|64|4" \
           "interior_19880|1920x1440|$I|32|4"; do
    IFS='|' read -r s size path spp passes <<< "$v"
    ORACLE_SIZE=$size mi $s cuda_ad_rgb $spp $passes
    python3 -c "import json; d=json.load(open('/tmp/mr/${s}_cuda_ad_rgb_$((spp*passes))spp.json')); print('mitsuba $s $size $round', round(d['Msamples_per_s'],1), 'render_s', round(d['render_s'],3))"
    b=4; [ $s = interior_19880 ] && b=6
    FURNACE_SHADER_CHECKS=unchecked bench "furnace $s $size $round" fn --scene $path --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --spp $((spp*passes))
  done
done
tar -czf $OUT/results.tgz -C $W . 2>/dev/null

#!/bin/bash
# Second profile run (same inputs as speed-profile.sh): invocations per pixel on every scene, the
# traversal stack's size and the trace counters' cost, equal-settings light sampling against
# Mitsuba, and the window-lit interior against Mitsuba.
# Measured with a2ecedf's kernel (a 32-entry stack, the default then) plus the environment
# overrides; with later binaries the FURNACE_TRV_STACK=32 runs are that kernel.
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-new.xz > /tmp/fn; xz -dc .dev/pipeline-stats.xz > /tmp/ps; chmod +x /tmp/fn /tmp/ps
[ -d /root/site/mitsuba ] || { mkdir -p /root/site && tar -xJf .mi/mitsuba-cuda.tar.xz -C /root/site; }
export PYTHONPATH=/root/site WAIT_IDLE=0 ORACLE_SEED_OFFSET=1000
R=$PWD/tests/data/references; I=/tmp/sc/interior_19880.gltf
W=/tmp/res; mkdir -p $W /tmp/sc /tmp/mo /tmp/mr
cp $R/lights/*.gltf $R/lights/*.bin $R/envmap/* .dev/sc/cbox.* .dev/sc/interior_19880.* /tmp/sc/
export ORACLE_SCENES=/tmp/sc ORACLE_OUT=/tmp/mo ORACLE_RESULTS=/tmp/mr
bench() {
  local name=$1; shift
  /tmp/fn bench --backend gpu "$@" --no-rays -q --json $W/b.json > $W/b.log 2>&1 || tail -2 $W/b.log
  python3 -c "import json; d=json.load(open('$W/b.json')); print('$name', round(d['msamples_per_s'],1), 'Ms/s', round(d.get('gpu_timestamp_ms_per_frame') or 0, 3), 'ms/frame gpu', d.get('gpu_group_samples'))"
}
echo "== pipeline statistics: stack 16, no trace counters"
for e in "FURNACE_TRV_STACK=16" "FURNACE_TRV_STACK=32 FURNACE_NO_TRACE_COUNTERS=1" "FURNACE_TRV_STACK=16 FURNACE_NO_TRACE_COUNTERS=1"; do
  env $e /tmp/ps cbox 2>&1 | grep -E 'Register|Local|Shared|Binary' | sed "s|^|$e: |"
done
scenes=("cbox256|--scene cbox --width 256 --height 256"
        "cbox1080|--scene cbox --width 1920 --height 1080"
        "area1080|--scene /tmp/sc/cbox_area.gltf --width 1920 --height 1080"
        "many1080|--scene /tmp/sc/cbox_many_lights.gltf --width 1920 --height 1080"
        "env1080|--scene /tmp/sc/envmap_spheres.gltf --width 1920 --height 1080"
        "int1080b4|--scene $I --width 1920 --height 1080"
        "int1440b6|--scene $I --width 1920 --height 1440 --bounces 6")
echo "== invocations per pixel (random sampler)"
for sc in "${scenes[@]}"; do for g in 1 2 4 8 16; do
  bench "${sc%%|*} group $g" ${sc#*|} --sampler random --min-seconds 1.5 --group-samples $g
done; done
echo "== stack 32/16, trace counters on/off (group 1 and the default)"
for sc in "${scenes[1]}" "${scenes[2]}" "${scenes[6]}"; do for g in 1 default; do
  ga="--group-samples $g"; [ $g = default ] && ga=""
  for e in "FURNACE_TRV_STACK=32" "FURNACE_TRV_STACK=16" "FURNACE_TRV_STACK=32 FURNACE_NO_TRACE_COUNTERS=1" "FURNACE_TRV_STACK=16 FURNACE_NO_TRACE_COUNTERS=1"; do
    env $e bash -c "$(declare -f bench); W=$W bench '${sc%%|*} $g $e' ${sc#*|} --sampler random --min-seconds 1.5 $ga"
  done
done; done
echo "== light sampling settings (1080p, random)"
for s in cbox_area cbox_many_lights; do
  for o in "" "--light-selection power" "--light-selection power --triangle-sampling area" "--light-sampling bsdf"; do
    bench "$s [$o]" --scene /tmp/sc/$s.gltf --width 1920 --height 1080 --sampler random --min-seconds 1.5 $o
  done
done
echo "== Mitsuba interior and lights, furnace beside"
mi() { (cd .dev/oracle && python3 render_ref.py "$@" > /tmp/mi.log 2>&1) || tail -5 /tmp/mi.log; }
for v in "interior_19880|1920x1440|$I|32|4|6" "interior_19880|1920x1080|$I|64|4|4" "cbox_area|1920x1080|/tmp/sc/cbox_area.gltf|64|4|4" "cbox_many_lights|1920x1080|/tmp/sc/cbox_many_lights.gltf|64|4|4"; do
  IFS='|' read -r s size path spp passes b <<< "$v"
  extra=""; [ $s = interior_19880 ] && [ $b = 4 ] && extra="--max-depth=5"
  ORACLE_SIZE=$size mi $s cuda_ad_rgb $spp $passes $extra
  python3 -c "import json; d=json.load(open('/tmp/mr/${s}_cuda_ad_rgb_$((spp*passes))spp.json')); print('mitsuba $s $size', round(d['Msamples_per_s'],1), 'render_s', round(d['render_s'],3))"
  for g in 1 default; do ga="--group-samples $g"; [ $g = default ] && ga=""
    bench "furnace $s $size group $g" --scene $path --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --spp $((spp*passes)) $ga
  done
  [ $s = interior_19880 ] || bench "furnace $s $size power+area" --scene $path --width ${size%x*} --height ${size#*x} --sampler random --spp $((spp*passes)) --light-selection power --triangle-sampling area
done
cp /tmp/mo/interior*.png $W/ 2>/dev/null
tar -czf $OUT/results.tgz -C $W . 2>/dev/null

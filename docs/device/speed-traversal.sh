#!/bin/bash
# The traversal's node test and loads, interleaved on the H200: `old` (a loop over the eight
# child slots, the node and triangle structs read field by field), `a` (the eight slots written
# out), `b` (a + nodes and triangles read as 16-byte words), each with wgpu's loop counters
# (the hardware default) and, for a and b, without; then the driver's statistics of b.
# Binaries (release, stripped, xz): old = 93a9269 (the looped test), b = 7ac2548, a = 7ac2548
# with `trv_node(..)` / `trv_triangle(..)` read back as `bvh_nodes[..]` / `bvh_triangles[..]`
# (structs again in `binding_list`). Needs .gl/, .dev/furnace-{old,a,b}.xz,
# .dev/pipeline-stats.xz (built from b) and .dev/sc/{cbox,interior_19880}.* (make_interior.py
# .dev/sc 2e4).
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
for b in ${BINS:-old a b}; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
[ -n "$QUICK" ] || { xz -dc .dev/pipeline-stats.xz > /tmp/ps; chmod +x /tmp/ps; }
R=$PWD/tests/data/references; I=/tmp/sc/interior_19880.gltf
W=/tmp/res; mkdir -p $W /tmp/sc
cp $R/lights/*.gltf $R/lights/*.bin $R/envmap/* .dev/sc/cbox.* .dev/sc/interior_19880.* /tmp/sc/
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
bench() {
  local name=$1 bin=$2; shift 2
  /tmp/$bin bench --backend gpu "$@" --no-rays -q --json $W/b.json > $W/b.log 2>&1 || tail -2 $W/b.log
  python3 -c "import json; d=json.load(open('$W/b.json')); print('$name', round(d['msamples_per_s'],1), 'Ms/s', round(d.get('gpu_timestamp_ms_per_frame') or 0, 3), 'ms/frame gpu, group', d.get('gpu_group_samples'))"
}
scenes=("cbox256|--scene cbox --width 256 --height 256"
        "cbox1080|--scene cbox --width 1920 --height 1080"
        "area1080|--scene /tmp/sc/cbox_area.gltf --width 1920 --height 1080"
        "many1080|--scene /tmp/sc/cbox_many_lights.gltf --width 1920 --height 1080"
        "env1080|--scene /tmp/sc/envmap_spheres.gltf --width 1920 --height 1080"
        "int1080b4|--scene $I --width 1920 --height 1080"
        "int1440b6|--scene $I --width 1920 --height 1440 --bounces 6")
# ONLY="name ...": those scenes alone; ROUNDS (2), BINS ("old a b"), MIN_S (1.5); QUICK=1 skips
# the noloop runs and the statistics (a short device budget).
echo "== ${BINS:-old a b}, random sampler, ${ROUNDS:-2} rounds"
for round in $(seq ${ROUNDS:-2}); do for sc in "${scenes[@]}"; do
  if [ -n "$ONLY" ] && [[ " $ONLY " != *" ${sc%%|*} "* ]]; then continue; fi
  for b in ${BINS:-old a b}; do
    bench "${sc%%|*} $b $round" f$b ${sc#*|} --sampler random --min-seconds ${MIN_S:-1.5}
done; done; done
[ -n "$QUICK" ] && exit 0
echo "== a / b without loop counters"
for sc in "${scenes[1]}" "${scenes[2]}" "${scenes[6]}"; do for b in a b; do
  FURNACE_SHADER_CHECKS=noloop bench "${sc%%|*} $b-noloop" f$b ${sc#*|} --sampler random --min-seconds ${MIN_S:-1.5}
done; done
echo "== pipeline statistics of b"
for s in cbox /tmp/sc/cbox_area.gltf $I; do for c in checked noloop; do
  /tmp/ps $s --checks $c 2>&1 | grep -v '^device' | sed "s|^|$(basename $s) $c: |"
done; done

#!/bin/bash
# Instancing and large scenes on the device host: the instanced forest (`forest:N`) on the GPU
# and the CPU, the flattened forest where it fits (`--flatten`), and the first frame in its
# parts (scene, BVH, default-light probe, opening, first pass) of the 10⁷- and 10⁸-triangle
# interiors. One furnace binary; prints each `furnace bench` table.
#
#   bash docs/device/instancing.sh .dev/furnace-after.xz
#
# WIDTH x HEIGHT (1920 x 1080), SPP (64); FORESTS, instanced on both backends ("20 2300 230000":
# about 10⁶, 10⁸ and 10¹⁰ placed triangles); FLAT_GPU ("20 2300") and FLAT_CPU ("20"), the
# flattened forests; INTERIORS ("1e7 1e8", on the GPU; the CPU renders the first).
set -u
source "$(dirname "$0")/env.sh"
unpack "$1"
f=${bins[0]}
size="--width ${WIDTH:-1920} --height ${HEIGHT:-1080}"
run() { echo "## $*"; timeout 300 "$f" bench "$@" --no-rays 2>&1 | grep -v '^benchmarking' | grep -E '^\| (gpu|cpu)|^memory|^first frame|rror'; }
for n in ${FORESTS:-20 2300 230000}; do
  run --backend gpu --scene forest:$n $size --spp "${SPP:-64}"
  run --backend cpu --scene forest:$n $size --spp 4
done
for n in ${FLAT_GPU:-20 2300}; do run --backend gpu --scene forest:$n $size --spp "${SPP:-64}" --flatten; done
for n in ${FLAT_CPU:-20}; do run --backend cpu --scene forest:$n $size --spp 4 --flatten; done
first=1
for n in ${INTERIORS:-1e7 1e8}; do
  run --backend gpu --scene interior:$n $size --spp 16
  [ $first = 1 ] && run --backend cpu --scene interior:$n $size --spp 1
  first=0
done

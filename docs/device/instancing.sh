#!/bin/bash
# Instancing on the device host: the forest at 10³, 10⁵ and 2.3·10⁵ instances (4.4·10⁷, 4.3·10⁹
# and 9.9·10⁹ placed triangles) on the GPU and the CPU, the flattened forest where it fits
# (`--flatten`), and the first frame of the 10⁷-triangle interior in its parts. One furnace
# binary; prints each `furnace bench` table.
#
#   bash docs/device/instancing.sh .dev/furnace-after.xz
#
# WIDTH x HEIGHT (1920 x 1080), SPP (64), FORESTS ("1000 100000 230000"), FLAT ("100 1000").
set -u
source "$(dirname "$0")/env.sh"
unpack "$1"
f=${bins[0]}
size="--width ${WIDTH:-1920} --height ${HEIGHT:-1080}"
run() { echo "## $*"; timeout 300 "$f" bench "$@" --no-rays 2>&1 | grep -v '^benchmarking' | grep -E '^\| (gpu|cpu)|^memory|^first frame|rror'; }
for n in ${FORESTS:-1000 100000 230000}; do
  run --backend gpu --scene forest:$n $size --spp "${SPP:-64}"
done
for n in ${FLAT:-100 1000}; do
  run --backend gpu --scene forest:$n $size --spp "${SPP:-64}"
  run --backend gpu --scene forest:$n $size --spp "${SPP:-64}" --flatten
  run --backend cpu --scene forest:$n $size --spp 4
  run --backend cpu --scene forest:$n $size --spp 4 --flatten
done
run --backend cpu --scene forest:230000 $size --spp 4
run --backend gpu --scene interior:1e7 $size --spp 16
run --backend cpu --scene interior:1e7 $size --spp 1

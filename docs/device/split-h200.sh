#!/bin/bash
# Split renders on the H200: one GPU run against a 4-way split of the same samples run one
# after the other (cbox_area, 1920x1080, 8 bounces, 1024 spp), the merged image against the single
# run, what a part costs beyond its samples (start-up), and --adapter by PCI address (what
# slurm/render-part.sbatch passes). Needs .dev/furnace-split.xz (a stripped release build).
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-split.xz > /tmp/f; chmod +x /tmp/f
S=tests/data/references/lights/cbox_area.gltf
W=/tmp/w; mkdir -p $W
nvidia-smi --query-gpu=name,driver_version,pci.bus_id --format=csv,noheader
bus=$(nvidia-smi --query-gpu=pci.bus_id --format=csv,noheader -i 0)
echo "adapter by PCI address $bus:"
opts=(--backend gpu --adapter "$bus" --width 1920 --height 1080 --bounces 8)
/tmp/f render $S "${opts[@]}" --spp 16 --out $W/warm 2>&1 | grep -E "rendering on|Msamples"
now() { date +%s.%N; }
sub() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a - b }'; }
for round in 1 2; do
  echo "== round $round"
  s=$(now); /tmp/f render $S "${opts[@]}" --spp 1024 --out $W/single 2>&1 | grep Msamples; e=$(now)
  echo "single run: $(sub $e $s) s wall"
  s=$(now)
  for k in 0 1 2 3; do
    /tmp/f render $S "${opts[@]}" --spp 1024 --samples $((k * 256))..$(((k + 1) * 256)) --out $W/part-$k 2>&1 | grep Msamples
  done
  m=$(now)
  /tmp/f merge $W/part-0.exr $W/part-1.exr $W/part-2.exr $W/part-3.exr -o $W/merged
  e=$(now)
  echo "4 parts: $(sub $m $s) s wall, merge $(sub $e $m) s"
  /tmp/f compare $W/merged.exr $W/single.exr | grep -E "RMSE|relative MSE"
done
echo "== 64 parts of 16 spp (start-up cost per part)"
s=$(now)
for k in $(seq 0 63); do
  /tmp/f render $S "${opts[@]}" --spp 1024 --samples $((k * 16))..$(((k + 1) * 16)) --out $W/p64-$k --quiet
done
m=$(now)
/tmp/f merge $W/p64-*.exr -o $W/merged64 --quiet
e=$(now)
echo "64 parts: $(sub $m $s) s wall, merge $(sub $e $m) s"
/tmp/f compare $W/merged64.exr $W/single.exr | grep -E "RMSE|relative MSE"

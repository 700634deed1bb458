#!/bin/bash
# Whether the film depends on the workgroup size on the H200 (FURNACE_GROUP_SIZE 256 against
# 1024): cbox_area 256² by light BVH and by power at 16 and 1024 spp (Owen-Sobol), each scored
# against the Mitsuba reference and against the other size; the built-in box likewise. Needs
# .gl/, .dev/furnace-new.xz (with the override), .dev/sc/.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
ref=$R/lights/cbox_area_ref_bounces4.exr
o="--backend gpu --width 256 --height 256 --masking separable --compensation off -q"
score() { /tmp/fnew compare "$@" | awk '/^RMSE/{r=$2} /^mean ratio/{m=$4" "$6" "$8} END{print "RMSE", r, "ratio", m}'; }
for sel in bvh power; do for spp in 16 1024; do for g in 256 1024; do
  FURNACE_GROUP_SIZE=$g /tmp/fnew render /tmp/sc/cbox_area.gltf $o --spp $spp --light-selection $sel --out $OUT/area_${sel}_${spp}_$g.exr > /dev/null 2>&1
  echo "cbox_area $sel $spp spp group $g vs reference: $(score $OUT/area_${sel}_${spp}_$g.exr $ref)"
done
  echo "cbox_area $sel $spp spp group 1024 vs 256: $(score $OUT/area_${sel}_${spp}_1024.exr $OUT/area_${sel}_${spp}_256.exr)"
done; done
for g in 256 1024; do FURNACE_GROUP_SIZE=$g /tmp/fnew render $o --spp 64 --out /tmp/box_$g.exr > /dev/null 2>&1; done
echo "cbox 64 spp group 1024 vs 256: $(score /tmp/box_1024.exr /tmp/box_256.exr)"
rm -f $OUT/*_1024_*.exr $OUT/*_16_*.exr 2>/dev/null; ls $OUT

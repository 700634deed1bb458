#!/bin/bash
# Accuracy at full size: furnace renders every reference scene at the reference's size and
# bounce count, with the references' material model (--masking separable --compensation off),
# and `furnace compare` scores it against the 65 536-spp Mitsuba reference and its standard
# error (image mean ratio per channel, z mean and std: ≈ √2 expected at equal sample counts,
# since the z uses the reference's error only). One device command.
#
#   bash docs/device/references.sh .dev/furnace.xz
#
# SPP (65536), BACKEND (gpu; cpu works too, slowly), SAMPLER (sobol), SCENES (default all:
# cbox cbox_direct cbox_area cbox_many_lights cbox_point cbox_sun_disc envmap_spheres glass_box
# glass_absorb). The EXRs are left in $OUT when the device sets it. Needs .gl/ and the binary.
set -u
source docs/device/env.sh
unpack "$1"
f=${bins[0]}
out=${OUT:-/tmp/references}; mkdir -p "$out"
want=${SCENES:-cbox cbox_direct cbox_area cbox_many_lights cbox_point cbox_sun_disc envmap_spheres glass_box glass_absorb}
echo "| scene | size | bounces | spp | render s | mean ratio R, G, B | z mean | z std |"
echo "|---|---|---|---|---|---|---|---|"
for s in $want; do
  case $s in
    cbox) scene=""; ref=$REF/cbox/cbox_ref_bounces4; size=256x256; b=4 ;;
    cbox_direct) scene=""; ref=$REF/cbox/cbox_ref_direct; size=256x256; b=1 ;;
    envmap_spheres) scene=$SC/$s.gltf; ref=$REF/envmap/${s}_ref_bounces4; size=320x240; b=4 ;;
    glass_*) scene=$SC/$s.gltf; ref=$REF/glass/${s}_ref_bounces8; size=256x256; b=8 ;;
    *) scene=$SC/$s.gltf; ref=$REF/lights/${s}_ref_bounces4; size=256x256; b=4 ;;
  esac
  start=$EPOCHREALTIME
  $f render $scene --backend "${BACKEND:-gpu}" --width ${size%x*} --height ${size#*x} --bounces $b \
    --spp "${SPP:-65536}" --sampler "${SAMPLER:-sobol}" --masking separable --compensation off \
    --out "$out/$s" -q > /tmp/r.log 2>&1 || tail -2 /tmp/r.log
  t=$(python3 -c "print(round($EPOCHREALTIME - $start))")
  $f compare "$out/$s.exr" "$ref.exr" --stderr "${ref}_stderr.exr" > /tmp/c.txt
  ratio=$(grep "^mean ratio" /tmp/c.txt | awk '{print $4", "$6", "$8}')
  zm=$(grep "^z mean" /tmp/c.txt | awk '{print $3}'); zs=$(grep "^z std" /tmp/c.txt | awk '{print $3}')
  echo "| $s | $size | $b | ${SPP:-65536} | $t | $ratio | $zm | $zs |"
done

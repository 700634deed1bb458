#!/bin/bash
# Glass on the H200: both glass references at full size on the GPU (tests/mitsuba.rs's ignored
# GPU test), furnace and Mitsuba 3 (cuda_ad_rgb, volpath for glass) interleaved on the Cornell
# box with and without its glass objects (1920x1080, 8 bounces), scenes without transmission
# against the previous binary (they must pay nothing), and error against time at 256^2.
# Needs .dev/furnace-new.xz, .dev/furnace-old.xz, .dev/mitsuba-test.xz (the stripped
# furnace-tests `all` test binary, test profile: its `mitsuba` module), .dev/oracle/ and .mi/mitsuba-cuda.tar.xz (README here),
# and .dev/sc/cbox.{gltf,bin} (the Cornell box's glTF from the shared references, for Mitsuba).
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
for b in new old; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
xz -dc .dev/mitsuba-test.xz > /tmp/mt; chmod +x /tmp/mt
# The checkout, Mitsuba and the binaries together exceed the device tree's 64 MiB: a first command
# carrying only .mi/ and .gl/ unpacks Mitsuba to /root/site (`tar -xJf .mi/mitsuba-cuda.tar.xz
# -C /root/site`), and this script follows within the machine's idle release without .mi/.
if [ ! -d /root/site/mitsuba ]; then mkdir -p /root/site && tar -xJf .mi/mitsuba-cuda.tar.xz -C /root/site; fi
export PYTHONPATH=/root/site WAIT_IDLE=0 ORACLE_SEED_OFFSET=1000
G=$PWD/tests/data/references/glass; L=$PWD/tests/data/references/lights
W=/tmp/res; mkdir -p $W /tmp/sc /tmp/mo /tmp/mr
cp $G/*.gltf $G/*.bin .dev/sc/cbox.gltf .dev/sc/cbox.bin /tmp/sc/
export ORACLE_SCENES=/tmp/sc ORACLE_OUT=/tmp/mo ORACLE_RESULTS=/tmp/mr
mi() { (cd .dev/oracle && python3 render_ref.py "$@" > /tmp/mi.log 2>&1) || tail -5 /tmp/mi.log; }
save() { tar -czf $OUT/results.tgz -C $W .; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
echo "== the GPU against Mitsuba's glass references, 256^2, 512 passes x 128 spp"
[ "$PWD" = /work/main ] || { mkdir -p /work/main && ln -sfn $PWD/tests /work/main/tests; }
(cd /work/main/tests && timeout 300 /tmp/mt --ignored --exact mitsuba::glass_matches_mitsuba_gpu --nocapture 2>&1 | grep -v XDG | grep -E '^\||test result|panicked' )
save
echo "== 1920x1080, 8 bounces, 256 spp: Mitsuba and furnace interleaved (cbox = the box with the metal sphere, no glass)"
for round in 1 2; do
  for s in cbox glass_box glass_absorb; do
    ORACLE_SIZE=1920x1080 mi $s cuda_ad_rgb 64 4 --max-depth=9
    python3 -c "import json; d=json.load(open('/tmp/mr/${s}_maxdepth9_cuda_ad_rgb_256spp.json')); print('mitsuba $s $round', round(d['Msamples_per_s'],1), 'render_s', round(d['render_s'],3))"
    sc=/tmp/sc/$s.gltf
    for smp in sobol random; do
      /tmp/fnew bench --backend gpu --scene $sc --width 1920 --height 1080 --sampler $smp --spp 256 --bounces 8 --no-rays -q --json $W/b_${s}_${smp}_$round.json > /dev/null 2>&1
      python3 -c "import json; d=json.load(open('$W/b_${s}_${smp}_$round.json')); print('furnace $smp $s $round', round(d['msamples_per_s'],1), 'seconds', round(d['seconds'],3))"
    done
  done
done
save
echo "== scenes without transmission, 1920x1080: the previous binary and this one interleaved"
for round in 1 2 3; do for s in cbox $L/cbox_area.gltf; do for b in old new; do
  if [ $s = cbox ]; then sc=""; else sc="--scene $s"; fi
  /tmp/f$b bench --backend gpu $sc --width 1920 --height 1080 --sampler sobol --spp 256 --no-rays -q --json $W/o_$b.json > /dev/null 2>&1
  python3 -c "import json; d=json.load(open('$W/o_$b.json')); print('$b $(basename $s) $round', round(d['msamples_per_s'],1))"
done; done; done
save
for s in glass_box glass_absorb; do
  echo "== $s 256^2 error vs spp and time: Mitsuba points, then furnace's chart"
  echo "label,spp,seconds,rmse,relmse" > $W/mitsuba_$s.csv
  for spp in 4 16 64 256 1024; do
    ORACLE_SIZE=256x256 mi $s cuda_ad_rgb $spp 1 --max-depth=9
    t=$(python3 -c "import json; print(json.load(open('/tmp/mr/${s}_maxdepth9_cuda_ad_rgb_${spp}spp.json'))['render_s'])")
    /tmp/fnew compare /tmp/mo/${s}_maxdepth9_cuda_ad_rgb_${spp}spp.exr $G/${s}_ref_bounces8.exr > /tmp/cmp.txt
    rmse=$(awk '/^RMSE/{print $2}' /tmp/cmp.txt); rel=$(awk '/^relative MSE/{print $3}' /tmp/cmp.txt)
    echo "mitsuba cuda_ad_rgb,$spp,$t,$rmse,$rel" | tee -a $W/mitsuba_$s.csv
  done
  /tmp/fnew chart --reference $G/${s}_ref_bounces8.exr --scene $G/$s.gltf --masking separable --compensation off --samplers sobol,random --sampling caps --spp 1024 --bounces 8 --backends gpu --external $W/mitsuba_$s.csv --out $W/chart_$s -q > $W/chart_$s.log 2>&1 || tail -3 $W/chart_$s.log
  cut -d, -f1-9 $W/chart_$s/chart.csv | head -20
  save
done
/tmp/fnew render $G/glass_box.gltf --backend gpu --spp 4096 --bounces 8 --width 512 --out $W/glass_box_512 -q
save
ls -la $OUT

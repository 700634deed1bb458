#!/bin/bash
# furnace and Mitsuba 3 (cuda_ad_rgb) interleaved in one run: equal-sample speed at 1920x1080 and
# error vs time at 256^2 on the emitter references; cbox old/new (no emitters) again.
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-new.xz > /tmp/fn; xz -dc .dev/furnace-old.xz > /tmp/fo; chmod +x /tmp/fn /tmp/fo
mkdir -p /tmp/site && tar -xJf .mi/mitsuba-cuda.tar.xz -C /tmp/site
export PYTHONPATH=/tmp/site WAIT_IDLE=0 ORACLE_SEED_OFFSET=1000
R=$PWD/tests/data/references/lights
W=/tmp/res; mkdir -p $W /tmp/sc /tmp/mo /tmp/mr
cp $R/*.gltf $R/*.bin /tmp/sc/
export ORACLE_SCENES=/tmp/sc ORACLE_OUT=/tmp/mo ORACLE_RESULTS=/tmp/mr
mi() { (cd .dev/oracle && python3 render_ref.py "$@" > /tmp/mi.log 2>&1) || tail -5 /tmp/mi.log; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
echo "== cbox 1920x1080 old/new interleaved (no emitters)"
for round in 1 2 3; do for smp in random sobol; do for b in fo fn; do
  /tmp/$b bench --backend gpu --scene cbox --width 1920 --height 1080 --sampler $smp --min-seconds 3 --no-rays -q --json $W/cbox_${b}_${smp}_$round.json > /dev/null 2>&1
  python3 -c "import json; d=json.load(open('$W/cbox_${b}_${smp}_$round.json')); print('$b $smp $round', round(d['msamples_per_s'],1), d['spp'])"
done; done; done
for s in cbox_area cbox_many_lights; do
  echo "== $s 1920x1080, 256 spp: Mitsuba and furnace interleaved"
  for round in 1 2; do
    ORACLE_SIZE=1920x1080 mi $s cuda_ad_rgb 64 4
    python3 -c "import json; d=json.load(open('/tmp/mr/${s}_cuda_ad_rgb_256spp.json')); print('mitsuba $s $round', round(d['Msamples_per_s'],1), 'render_s', round(d['render_s'],3))"
    for smp in sobol random; do
      /tmp/fn bench --backend gpu --scene $R/$s.gltf --width 1920 --height 1080 --sampler $smp --spp 256 --no-rays -q --json $W/b_${s}_${smp}_$round.json > /dev/null 2>&1
      python3 -c "import json; d=json.load(open('$W/b_${s}_${smp}_$round.json')); print('furnace $smp $s $round', round(d['msamples_per_s'],1), 'seconds', round(d['seconds'],3))"
    done
  done
  echo "== $s 256^2 error vs spp and time: Mitsuba points"
  echo "label,spp,seconds,rmse,relmse" > $W/mitsuba_$s.csv
  for spp in 4 16 64 256 1024; do
    ORACLE_SIZE=256x256 mi $s cuda_ad_rgb $spp 1
    t=$(python3 -c "import json; print(json.load(open('/tmp/mr/${s}_cuda_ad_rgb_${spp}spp.json'))['render_s'])")
    /tmp/fn compare /tmp/mo/${s}_cuda_ad_rgb_${spp}spp.exr $R/${s}_ref_bounces4.exr > /tmp/cmp.txt
    rmse=$(awk '/^RMSE/{print $2}' /tmp/cmp.txt); rel=$(awk '/^relative MSE/{print $3}' /tmp/cmp.txt)
    echo "mitsuba cuda_ad_rgb,$spp,$t,$rmse,$rel" | tee -a $W/mitsuba_$s.csv
  done
  /tmp/fn chart --reference $R/${s}_ref_bounces4.exr --scene $R/$s.gltf --masking separable --compensation off --samplers sobol,random --sampling caps --light-sampling bsdf,nee,mis --spp 1024 --backends gpu --external $W/mitsuba_$s.csv --out $W/chart_$s -q > $W/chart_$s.log 2>&1 || tail -3 $W/chart_$s.log
  cut -d, -f1-9 $W/chart_$s/chart.csv | head -40
done
cp /tmp/mo/*1024spp.png $W/ 2>/dev/null
tar -czf $OUT/results.tgz -C $W .
ls -la $OUT

#!/bin/bash
# Emitter selection by power (alias table) against the light BVH on the H200, with Mitsuba 3
# (cuda_ad_rgb, uniform emitter choice) interleaved in the same run: equal-sample speed at
# 1920x1080, error vs spp and time at 256^2 (furnace chart --light-selection, Mitsuba as
# --external points), the same on two real assets against a 16384-spp furnace render of their
# own, and the full-size agreement with the references under the new default (BVH).
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-new.xz > /tmp/fn; chmod +x /tmp/fn
mkdir -p /tmp/site && tar -xJf .mi/mitsuba-cuda.tar.xz -C /tmp/site
export PYTHONPATH=/tmp/site WAIT_IDLE=0 ORACLE_SEED_OFFSET=1000
R=$PWD/tests/data/references/lights
W=/tmp/res; mkdir -p $W /tmp/sc /tmp/mo /tmp/mr
cp $R/*.gltf $R/*.bin /tmp/sc/
export ORACLE_SCENES=/tmp/sc ORACLE_OUT=/tmp/mo ORACLE_RESULTS=/tmp/mr
save() { tar -czf $OUT/results.tgz -C $W .; }  # after each section: a timeout keeps what is done
mi() { (cd .dev/oracle && python3 render_ref.py "$@" > /tmp/mi.log 2>&1) || tail -5 /tmp/mi.log; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
for s in cbox_area cbox_many_lights; do
  echo "== $s 1920x1080, 256 spp: Mitsuba and furnace (power, bvh) interleaved"
  for round in 1 2; do
    ORACLE_SIZE=1920x1080 mi $s cuda_ad_rgb 64 4
    python3 -c "import json; d=json.load(open('/tmp/mr/${s}_cuda_ad_rgb_256spp.json')); print('mitsuba $s $round', round(d['Msamples_per_s'],1), 'render_s', round(d['render_s'],3))"
    for smp in sobol random; do for ls in power bvh; do
      /tmp/fn bench --backend gpu --scene $R/$s.gltf --width 1920 --height 1080 --sampler $smp --light-selection $ls --spp 256 --no-rays -q --json $W/b_${s}_${smp}_${ls}_$round.json > /dev/null 2>&1
      python3 -c "import json; d=json.load(open('$W/b_${s}_${smp}_${ls}_$round.json')); print('furnace $smp $ls $s $round', round(d['msamples_per_s'],1), 'seconds', round(d['seconds'],3))"
    done; done
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
  /tmp/fn chart --reference $R/${s}_ref_bounces4.exr --scene $R/$s.gltf --masking separable --compensation off --samplers sobol,random --sampling caps --light-sampling mis --light-selection power,bvh --spp 1024 --backends gpu --external $W/mitsuba_$s.csv --out $W/chart_$s -q > $W/chart_$s.log 2>&1 || tail -3 $W/chart_$s.log
  grep -E ",(64|256|1024)," $W/chart_$s/chart.csv
  save
done
echo "== real assets: power vs bvh at 512^2 against a 16384-spp furnace render (bvh), speed at 1080p"
S=$PWD/tests/data/scenes
for a in CornellBox-cetra/cornell_box.gltf DamagedHelmet/glTF-Binary/DamagedHelmet.glb; do
  n=$(basename $(dirname $a)); [ "$n" = glTF-Binary ] && n=DamagedHelmet
  /tmp/fn render $S/$a --spp 16384 --width 512 --height 512 --backend gpu --out $W/ref_$n -q
  for ls in power bvh; do
    /tmp/fn bench --backend gpu --scene $S/$a --width 1920 --height 1080 --light-selection $ls --spp 256 --no-rays -q --json $W/b_${n}_$ls.json > /dev/null 2>&1
    python3 -c "import json; d=json.load(open('$W/b_${n}_$ls.json')); print('furnace sobol $ls $n 1080p', round(d['msamples_per_s'],1), 'seconds', round(d['seconds'],3))"
  done
  /tmp/fn chart --reference $W/ref_$n.exr --scene $S/$a --samplers sobol --sampling caps --light-selection power,bvh --spp 1024 --backends gpu --out $W/chart_$n -q > $W/chart_$n.log 2>&1 || tail -3 $W/chart_$n.log
  grep -E ",(64|256|1024)," $W/chart_$n/chart.csv
  rm -f $W/ref_$n.exr $W/ref_$n.png
  save
done
echo "== full size (256^2, 65536 spp, GPU, Sobol, MIS, solid angle, bvh) against the references"
for s in cbox_area cbox_many_lights; do
  /tmp/fn render $R/$s.gltf --spp 65536 --width 256 --masking separable --compensation off --backend gpu --out $W/full_$s -q
  /tmp/fn compare $W/full_$s.exr $R/${s}_ref_bounces4.exr --stderr $R/${s}_ref_bounces4_stderr.exr | sed -n 3,9p
done
rm -f $W/full_*.exr $W/full_*.png
save
ls -la $OUT

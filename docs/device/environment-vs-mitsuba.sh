#!/bin/bash
# Environment maps on the H200 with Mitsuba 3 (cuda_ad_rgb) interleaved in the same run: speed at
# 1920x1080, error against spp and time (furnace chart --env-sampling off,importance,compensated,
# Mitsuba's points as --external) on the environment-map reference scene and on the same scene
# under a map with a 0.1 deg sun in one texel of 2048x1024 (its reference rendered here by
# Mitsuba, 65 536 spp). Needs .dev/furnace-new.xz, .dev/oracle/, .mi/mitsuba-cuda.tar.xz.
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-new.xz > /tmp/fn; chmod +x /tmp/fn
mkdir -p /tmp/site && tar -xJf .mi/mitsuba-cuda.tar.xz -C /tmp/site
export PYTHONPATH=/tmp/site WAIT_IDLE=0
E=$PWD/tests/data/references/envmap
W=/tmp/res; mkdir -p $W /tmp/sc /tmp/mo /tmp/mr
cp $E/envmap_spheres.gltf $E/envmap_spheres.bin $E/envmap_spheres_env.exr /tmp/sc/
export ORACLE_SCENES=/tmp/sc ORACLE_OUT=/tmp/mo ORACLE_RESULTS=/tmp/mr
save() { tar -czf $OUT/results.tgz -C $W .; }
mi() { (cd .dev/oracle && python3 render_ref.py "$@" > /tmp/mi.log 2>&1) || tail -5 /tmp/mi.log; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
echo "== tiny-sun map and its Mitsuba reference (320x240, 1024 spp x 64 passes)"
python3 docs/device/make_env_maps.py tiny-sun /tmp/sc/tiny_sun_env.exr
sed 's/envmap_spheres_env.exr/tiny_sun_env.exr/' $E/envmap_spheres.gltf > /tmp/sc/tiny_sun.gltf
ORACLE_SEED_OFFSET=0 mi tiny_sun cuda_ad_rgb 1024 64
cp /tmp/mo/tiny_sun_cuda_ad_rgb_65536spp.exr $W/tiny_sun_ref.exr
cp /tmp/mo/tiny_sun_cuda_ad_rgb_65536spp_stderr.exr $W/tiny_sun_ref_stderr.exr
cp /tmp/sc/tiny_sun_env.exr $W/
python3 -c "import json; d=json.load(open('/tmp/mr/tiny_sun_cuda_ad_rgb_65536spp.json')); print('tiny sun reference', round(d['render_s'],1), 's, mean rel stderr', d.get('mean_rel_stderr'))"
save
export ORACLE_SEED_OFFSET=1000
for s in envmap_spheres tiny_sun; do
  if [ $s = envmap_spheres ]; then ref=$E/envmap_spheres_ref_bounces4.exr; else ref=$W/tiny_sun_ref.exr; fi
  echo "== $s 1920x1080, 256 spp: Mitsuba and furnace interleaved"
  for round in 1 2; do
    ORACLE_SIZE=1920x1080 mi $s cuda_ad_rgb 64 4
    python3 -c "import json; d=json.load(open('/tmp/mr/${s}_cuda_ad_rgb_256spp.json')); print('mitsuba $s $round', round(d['Msamples_per_s'],1), 'Msamples/s')"
    for smp in sobol random; do for es in off importance compensated; do
      /tmp/fn bench --backend gpu --scene /tmp/sc/$s.gltf --width 1920 --height 1080 --sampler $smp --env-sampling $es --spp 256 --no-rays -q --json $W/b.json > /dev/null 2>&1
      python3 -c "import json; d=json.load(open('$W/b.json')); print('furnace $smp $es $s $round', round(d['msamples_per_s'],1), 'Msamples/s')"
    done; done
  done
  echo "== $s 320x240 error against spp and time: Mitsuba's points, furnace chart"
  echo "label,spp,seconds,rmse,relmse" > $W/mitsuba_$s.csv
  for spp in 4 16 64 256 1024; do
    mi $s cuda_ad_rgb $spp 1
    t=$(python3 -c "import json; print(json.load(open('/tmp/mr/${s}_cuda_ad_rgb_${spp}spp.json'))['render_s'])")
    /tmp/fn compare /tmp/mo/${s}_cuda_ad_rgb_${spp}spp.exr $ref > /tmp/cmp.txt
    rmse=$(awk '/^RMSE/{print $2}' /tmp/cmp.txt); rel=$(awk '/^relative MSE/{print $3}' /tmp/cmp.txt)
    echo "mitsuba cuda_ad_rgb,$spp,$t,$rmse,$rel" | tee -a $W/mitsuba_$s.csv
  done
  /tmp/fn chart --reference $ref --scene /tmp/sc/$s.gltf --masking separable --compensation off --samplers sobol --sampling caps --env-sampling off,importance,compensated --spp 1024 --backends gpu --external $W/mitsuba_$s.csv --out $W/chart_$s -q > $W/chart_$s.log 2>&1 || tail -3 $W/chart_$s.log
  grep -E ",(16|64|256|1024)," $W/chart_$s/chart.csv
  save
done
echo "== full size: furnace 65536 spp against the tiny-sun reference"
/tmp/fn render /tmp/sc/tiny_sun.gltf --spp 65536 --width 320 --masking separable --compensation off --backend gpu --env-sampling compensated --out $W/full_tiny -q
/tmp/fn compare $W/full_tiny.exr $W/tiny_sun_ref.exr | sed -n 3,5p
rm -f $W/full_tiny*
save
ls -la $OUT

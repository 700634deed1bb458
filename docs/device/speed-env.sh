# Sourced by the docs/device/speed-*.sh scripts (from the repository root on the device): the
# Vulkan loaders, Mitsuba (when .mi/mitsuba-cuda.tar.xz travelled, or a first command unpacked
# it to /root/site), the reference scenes and the interior copied to /tmp/sc, and
#   bench NAME BIN ARGS...  one `furnace bench` of /tmp/BIN: prints Msamples/s, GPU ms per frame
#                           and the invocations per pixel;
#   mi ARGS...              the oracle's render_ref.py (ORACLE_* folders under /tmp);
#   mitsuba_at S WxH SPP P  Mitsuba's Msamples/s (run twice, the second quoted); `equal`: the
#                           configurations furnace is compared at equal samples;
#   scenes                  the benchmark configurations, "name|furnace arguments": the seven
#                           of the speed sections, then the point-light and sun-disc boxes.
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ ! -d /root/site/mitsuba ] && [ -f .mi/mitsuba-cuda.tar.xz ]; then
  mkdir -p /root/site && tar -xJf .mi/mitsuba-cuda.tar.xz -C /root/site
fi
export PYTHONPATH=/root/site WAIT_IDLE=0 ORACLE_SEED_OFFSET=1000
R=$PWD/tests/data/references; I=/tmp/sc/interior_19880.gltf
W=/tmp/res; mkdir -p $W /tmp/sc /tmp/mo /tmp/mr
cp $R/lights/*.gltf $R/lights/*.bin $R/envmap/* .dev/sc/cbox.* /tmp/sc/
cp .dev/sc/interior_19880.* /tmp/sc/ 2>/dev/null
export ORACLE_SCENES=/tmp/sc ORACLE_OUT=/tmp/mo ORACLE_RESULTS=/tmp/mr
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,clocks.max.mem --format=csv,noheader
bench() {
  local name=$1 bin=$2; shift 2
  /tmp/$bin bench --backend gpu "$@" --no-rays -q --json $W/b.json > $W/b.log 2>&1 || tail -2 $W/b.log
  python3 -c "import json; d=json.load(open('$W/b.json')); print('$name', round(d['msamples_per_s'],1), 'Ms/s', round(d.get('gpu_timestamp_ms_per_frame') or 0, 3), 'ms/frame gpu, group', d.get('gpu_group_samples'))"
}
mi() { (cd .dev/oracle && python3 render_ref.py "$@" > /tmp/mi.log 2>&1) || tail -5 /tmp/mi.log; }
# mitsuba_at SCENE WxH SPP PASSES: Mitsuba's Msamples/s over PASSES passes of SPP, rendered twice
# and the second quoted (the first runs on a GPU whose clocks dropped during the scene load).
mitsuba_at() {
  local s=$1 size=$2 spp=$3 passes=$4
  ORACLE_SIZE=$size mi $s cuda_ad_rgb $spp $passes
  ORACLE_SIZE=$size mi $s cuda_ad_rgb $spp $passes
  python3 -c "import json; d=json.load(open('/tmp/mr/${s}_cuda_ad_rgb_$((spp*passes))spp.json')); print('mitsuba $s $size', round(d['Msamples_per_s'],1), 'render_s', round(d['render_s'],3))"
}
# The equal-samples configurations against Mitsuba, "scene|WxH|furnace scene|spp|passes|bounces".
equal=("cbox|256x256|cbox|64|4|4" "cbox|1920x1080|cbox|64|4|4" "cbox_area|1920x1080|/tmp/sc/cbox_area.gltf|64|4|4"
       "cbox_many_lights|1920x1080|/tmp/sc/cbox_many_lights.gltf|64|4|4"
       "envmap_spheres|1920x1080|/tmp/sc/envmap_spheres.gltf|64|4|4" "interior_19880|1920x1440|$I|32|4|6"
       "cbox_point|1920x1080|/tmp/sc/cbox_point.gltf|64|4|4" "cbox_sun_disc|1920x1080|/tmp/sc/cbox_sun_disc.gltf|64|4|4")
scenes=("cbox256|--scene cbox --width 256 --height 256"
        "cbox1080|--scene cbox --width 1920 --height 1080"
        "area1080|--scene /tmp/sc/cbox_area.gltf --width 1920 --height 1080"
        "many1080|--scene /tmp/sc/cbox_many_lights.gltf --width 1920 --height 1080"
        "env1080|--scene /tmp/sc/envmap_spheres.gltf --width 1920 --height 1080"
        "int1080b4|--scene $I --width 1920 --height 1080"
        "int1440b6|--scene $I --width 1920 --height 1440 --bounces 6"
        "point1080|--scene /tmp/sc/cbox_point.gltf --width 1920 --height 1080"
        "disc1080|--scene /tmp/sc/cbox_sun_disc.gltf --width 1920 --height 1080")

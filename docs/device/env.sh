# Sourced by the scripts of docs/device/, from the repository root on the device machine:
# installs the Vulkan loader and glvnd from .gl/ (NVIDIA's Vulkan driver needs glvnd, or wgpu
# finds no adapter), prints the GPUs, and defines
#   unpack BIN...      each furnace binary (xz-compressed or not) copied to /tmp/furnace-K,
#                      K = 1, 2, ...; their paths in the array `bins`
#   mitsuba_setup      Mitsuba 3 cuda_ad_rgb importable (from MITSUBA_SITE, default /root/site,
#                      filled from .mi/*.tar.xz or .mi/*/*.tar.xz when it is empty) and the oracle
#                      (ORACLE, default shared/oracle or .dev/oracle: render_ref.py, cpuload.py);
#                      returns 1 when either is missing
#   mitsuba S WxH SPP PASSES [ARGS]   render_ref.py S cuda_ad_rgb (MITSUBA_VARIANT); prints
#                      its Msamples/s
# and the reference scenes: REF (tests/data/references), SC (/tmp/sc: the scenes copied with
# .dev/sc/cbox.{gltf,bin} and, when present, .dev/sc/interior_19880.{gltf,bin}).
for f in .gl/*.deb; do [ -f "$f" ] && dpkg -x "$f" / > /dev/null; done
ldconfig
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
nvidia-smi --query-gpu=index,name,driver_version,clocks.max.sm --format=csv,noheader
REF=$PWD/tests/data/references
SC=/tmp/sc
mkdir -p $SC /tmp/mo /tmp/mr
cp $REF/lights/*.gltf $REF/lights/*.bin $REF/envmap/*.gltf $REF/envmap/*.bin $REF/envmap/*_env.exr \
  $REF/glass/*.gltf $REF/glass/*.bin $SC/
cp .dev/sc/cbox.* .dev/sc/interior_19880.* $SC/ 2> /dev/null

bins=()
unpack() {
  local k=0 b
  for b in "$@"; do
    k=$((k + 1))
    case $b in
      *.xz) xz -dc "$b" > /tmp/furnace-$k ;;
      *) cp "$b" /tmp/furnace-$k ;;
    esac
    chmod +x /tmp/furnace-$k
    bins+=(/tmp/furnace-$k)
  done
}

mitsuba_setup() {
  local site=${MITSUBA_SITE:-/root/site} t
  if [ ! -d "$site/mitsuba" ]; then
    mkdir -p "$site"
    for t in .mi/*.tar.xz .mi/*/*.tar.xz; do [ -f "$t" ] && tar -xJf "$t" -C "$site"; done
  fi
  ORACLE=${ORACLE:-$([ -d shared/oracle ] && echo shared/oracle || echo .dev/oracle)}
  export PYTHONPATH=$site WAIT_IDLE=0 ORACLE_SCENES=$SC ORACLE_OUT=/tmp/mo ORACLE_RESULTS=/tmp/mr
  [ -d "$site/mitsuba" ] && [ -f "$ORACLE/render_ref.py" ]
}

mitsuba() {
  local s=$1 size=$2 spp=$3 passes=$4 depth
  shift 4
  local v=${MITSUBA_VARIANT:-cuda_ad_rgb}
  rm -f /tmp/mr/"${s}"_*"$v"_*.json
  (cd "$ORACLE" && ORACLE_SIZE=$size python3 render_ref.py "$s" "$v" "$spp" "$passes" "$@" > /tmp/mi.log 2>&1) \
    || { tail -3 /tmp/mi.log >&2; echo "-"; return; }
  python3 -c "import json, glob; print('%.1f' % json.load(open(glob.glob('/tmp/mr/${s}_*${v}_*spp.json')[0]))['Msamples_per_s'])"
}

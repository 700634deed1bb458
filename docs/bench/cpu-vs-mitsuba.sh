#!/bin/bash
# The CPU reference against Mitsuba 3's vectorised CPU variant (llvm_ad_rgb), interleaved in one
# run on one machine, random / independent samplers on both sides, all cores of the machine:
# the Cornell box of ../shared/references (cbox.gltf, 256x256, 4 bounces, Mitsuba max_depth 5)
# and, with INTERIOR=path/to/interior_19880.gltf (docs/device/make_interior.py), the window-lit
# interior (320x240, 6 bounces, max_depth 7).
#
#   docs/bench/cpu-vs-mitsuba.sh FURNACE_A [FURNACE_B ...]
#
# Each FURNACE is a `furnace` binary (e.g. target/release/furnace and one built from another
# commit); ROUNDS (default 3) rounds of: Mitsuba, then each binary, per scene. Mitsuba: the
# oracle's render_ref.py (../shared/oracle, `setup.sh` once; its JIT warm-up pass is excluded),
# 3 passes; furnace: `furnace bench --backend cpu --sampler random --no-rays` for at least 4 s
# (the mean rate of its passes, as Mitsuba's figure is).
#
# MITSUBA_AVX2=1 also runs Mitsuba with its JIT compiling for AVX2, 8 lanes (mitsuba_avx2.py):
# on an AVX-512 machine, what Mitsuba does on an AVX2 one, on the same cores.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
shared=${SHARED:-$here/../shared}
rounds=${ROUNDS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$shared/references/cbox/cbox.gltf" "$shared/references/cbox/cbox.bin" "$work/"
# name | WxH | bounces | Mitsuba spp per pass
configs=("cbox|256x256|4|64")
if [ -n "${INTERIOR:-}" ]; then
  cp "$INTERIOR" "${INTERIOR%.gltf}.bin" "$work/"
  configs+=("$(basename "${INTERIOR%.gltf}")|320x240|6|32")
fi
. "$shared/oracle/env.sh"
for round in $(seq "$rounds"); do
  for c in "${configs[@]}"; do
    IFS='|' read -r name size bounces spp <<< "$c"
    rm -f "$work"/*_llvm_ad_rgb_*.json
    ORACLE_SCENES=$work ORACLE_OUT=$work ORACLE_RESULTS=$work ORACLE_SIZE=$size WAIT_IDLE=5 \
      python "$shared/oracle/render_ref.py" "$name" llvm_ad_rgb "$spp" 3 --max-depth=$((bounces + 1)) > "$work/mitsuba.log" 2>&1
    mitsuba=$(python -c "import json,glob; print('%.3f' % json.load(open(glob.glob('$work/${name}_maxdepth*_llvm_ad_rgb_*.json')[0]))['Msamples_per_s'])")
    echo "round $round, $name $size: mitsuba llvm_ad_rgb $mitsuba Msamples/s"
    if [ -n "${MITSUBA_AVX2:-}" ]; then
      rm -f "$work"/*_llvm_ad_rgb_*.json
      ORACLE_SCENES=$work ORACLE_OUT=$work ORACLE_RESULTS=$work ORACLE_SIZE=$size WAIT_IDLE=5 \
        python "$here/docs/bench/mitsuba_avx2.py" "$shared/oracle/render_ref.py" "$name" llvm_ad_rgb "$spp" 3 \
        --max-depth=$((bounces + 1)) > "$work/mitsuba-avx2.log" 2>&1
      avx2=$(python -c "import json,glob; print('%.3f' % json.load(open(glob.glob('$work/${name}_maxdepth*_llvm_ad_rgb_*.json')[0]))['Msamples_per_s'])")
      echo "round $round, $name $size: mitsuba llvm_ad_rgb AVX2 x8 $avx2 Msamples/s"
    fi
    for bin in "$@"; do
      rate=$("$bin" bench --backend cpu --scene "$work/$name.gltf" --width "${size%x*}" --height "${size#*x}" \
        --sampler random --bounces "$bounces" --min-seconds 4 --no-rays --json - 2>/dev/null \
        | python -c "import json,sys; print('%.3f' % json.load(sys.stdin)['msamples_per_s'])")
      echo "round $round, $name $size: $bin $rate Msamples/s"
    done
  done
done

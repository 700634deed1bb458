#!/bin/bash
# The CPU reference against Mitsuba 3's vectorised CPU variant (llvm_ad_rgb), interleaved in one
# run on one machine: the Cornell box of ../shared/references (cbox.gltf, 256x256, 4 bounces,
# Mitsuba max_depth 5), independent / random samplers on both sides, all cores of the machine.
#
#   docs/bench/cpu-vs-mitsuba.sh FURNACE_A [FURNACE_B ...]
#
# Each FURNACE is a `furnace` binary (e.g. target/release/furnace and one built from another
# commit); ROUNDS (default 3) rounds of: Mitsuba, then each binary. Mitsuba: the oracle's
# render_ref.py (../shared/oracle, `setup.sh` once, JIT warm-up pass excluded), 64 spp x 3
# passes; furnace: `furnace bench --backend cpu --sampler random --no-rays` for at least 4 s (the
# mean rate of its passes, as Mitsuba's figure is).
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
shared=${SHARED:-$here/../shared}
rounds=${ROUNDS:-3}
work=$(mktemp -d)
cp "$shared/references/cbox/cbox.gltf" "$shared/references/cbox/cbox.bin" "$work/"
. "$shared/oracle/env.sh"
for round in $(seq "$rounds"); do
  ORACLE_SCENES=$work ORACLE_OUT=$work ORACLE_RESULTS=$work ORACLE_SIZE=256x256 WAIT_IDLE=5 \
    python "$shared/oracle/render_ref.py" cbox llvm_ad_rgb 64 3 --max-depth=5 > "$work/mitsuba.log" 2>&1
  mitsuba=$(python -c "import json,glob; print('%.3f' % json.load(open(glob.glob('$work/cbox_maxdepth5_llvm_ad_rgb_*.json')[0]))['Msamples_per_s'])")
  echo "round $round: mitsuba llvm_ad_rgb $mitsuba Msamples/s"
  for bin in "$@"; do
    rate=$("$bin" bench --backend cpu --scene "$work/cbox.gltf" --width 256 --height 256 --sampler random --bounces 4 \
      --min-seconds 4 --no-rays --json - 2>/dev/null | python -c "import json,sys; print('%.3f' % json.load(sys.stdin)['msamples_per_s'])")
    echo "round $round: $bin $rate Msamples/s"
  done
done
rm -rf "$work"

#!/bin/bash
# One render on several GPUs (`furnace render/bench --gpus`), for a machine with 2-8 GPUs:
# samples/s on 1, 2, 4 (8) GPUs for the Cornell box at 3840x2160 and a 10^7-triangle interior,
# scaling efficiency (rate on N / (N x rate on 1)), time to first frame (BVH built once, uploaded
# to each GPU in parallel), the devices' wait for the slowest of each pass's shares and the time
# of one collection of the film, each count run twice in alternating rounds; then the film on all GPUs
# against one GPU's at equal samples (same estimator: RMSE at f32 rounding), and with one GPU
# lost mid-render (FURNACE_LOSE_GPU). Needs .gl/ and the binary (README.md); no Mitsuba.
#
#   bash docs/device/multi-gpu.sh .dev/furnace.xz
#
# ROUNDS (2), MIN_S (10) and COUNTS ("1 2 4 8", cut to the GPUs present) shorten it.
# SAME_GPU=1 opens every device on GPU 0 instead (`--gpus 0,0,...`): on a one-GPU machine this
# measures what the several-device path costs (shares, collections, the slowest device's wait)
# where no speed-up is possible; the loss test then loses the second device on the same GPU.
source docs/device/env.sh
unpack "${1:-.dev/furnace-new.xz}"
cp "${bins[0]}" /tmp/f
W=/tmp/w; mkdir -p $W
nvidia-smi --query-gpu=index,pci.bus_id --format=csv,noheader
gpus=$(nvidia-smi --query-gpu=index --format=csv,noheader | wc -l)
/tmp/f bench --gpus all --width 8 --height 8 --spp 1 -q > /dev/null 2>&1  # driver warm-up
if [ -n "$SAME_GPU" ]; then
  list() { printf '0%.0s,' $(seq $1) | sed 's/,$//'; }
  gpus=8; all=0,0
else
  list() { seq -s, 0 $(($1 - 1)); }
  all=all
fi
bench() {
  local label=$1 n=$2; shift 2
  /tmp/f bench --gpus "$(list $n)" "$@" --no-rays --min-seconds ${MIN_S:-10} -q --json $W/b.json > $W/b.log 2>&1 || tail -3 $W/b.log
  python3 -c "import json; d=json.load(open('$W/b.json')); print('$label', 'gpus=$n', round(d['msamples_per_s'],1), 'Ms/s', 'first frame', round(d['time_to_first_frame_s'],2), 's', '(scene', round(d.get('first_frame_scene_s') or 0, 2), 'open', round(d.get('first_frame_open_s') or 0, 2), 'pass', round(d.get('first_frame_pass_s') or 0, 2), ')', 'gpu ms/frame', round(d.get('gpu_timestamp_ms_per_frame') or 0, 3), 'idle', round(d.get('gpus_idle') or 0, 3), 'busy', [round(g['busy'], 3) for g in d.get('gpus') or []], 'one collection', round(d.get('gpus_one_collection_seconds') or 0, 3), 's')"
}
configs=("cbox2160|--scene cbox --width 3840 --height 2160" "interior1e7|--scene interior:1e7 --width 1920 --height 1080 --bounces 6")
for round in $(seq 1 ${ROUNDS:-2}); do
  echo "== round $round"
  for c in "${configs[@]}"; do
    for n in ${COUNTS:-1 2 4 8}; do
      [ $n -le $gpus ] && bench "${c%%|*}" $n ${c#*|}
    done
  done
done
echo "== films: all GPUs against one, cbox 1920x1080, 256 spp"
/tmp/f render --gpus 0 --width 1920 --height 1080 --spp 256 --out $W/one 2>&1 | grep Msamples
/tmp/f render --gpus $all --width 1920 --height 1080 --spp 256 --out $W/all 2>&1 | grep -E "rendering on|Msamples"
/tmp/f compare $W/all.exr $W/one.exr | grep -E "RMSE|ratio"
# A 1080p render of 256 spp on an H200 takes ~10 passes (they grow to fill 0.1 s), so the loss
# is set early enough to happen.
echo "== a GPU lost mid-render (FURNACE_LOSE_GPU=1@3: device 1 destroyed before pass 3): the render finishes"
FURNACE_LOSE_GPU=1@3 /tmp/f render --gpus $all --width 1920 --height 1080 --spp 256 --out $W/lost 2>&1 | grep -E "warning: GPU|Msamples"
/tmp/f compare $W/lost.exr $W/one.exr | grep -E "RMSE|ratio"

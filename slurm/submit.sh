#!/usr/bin/env bash
# Renders a scene split over a Slurm job array and merges it:
#
#   slurm/submit.sh --tasks K --spp N --dir DIR [--sbatch "OPTIONS"] [--merge "OPTIONS"] \
#       -- [SCENE.gltf] [furnace render options]
#
# submits K array tasks (slurm/render-part.sbatch: task k renders samples k·N/K … (k+1)·N/K − 1
# into DIR/part-k.exr, resuming it when requeued) and one merge job that runs after them
# (slurm/merge.sbatch, --dependency=afterany) and writes DIR/merged.exr and .png. Prints the two
# job ids ("ARRAY MERGE"). --sbatch options go to every job (partition, account, --gres=gpu:1,
# --cpus-per-task …); --merge options to `furnace merge` (--allow-gaps …). FURNACE_BIN names the
# binary (default: `furnace` on PATH), FURNACE_CHECKPOINT the seconds between saves.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
tasks='' spp='' dir='' sbatch_opts='' merge_opts=''
while (($#)); do
  case $1 in
    --tasks) tasks=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --dir) dir=$2; shift 2 ;;
    --sbatch) sbatch_opts=$2; shift 2 ;;
    --merge) merge_opts=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "submit.sh: unknown option $1 (usage: submit.sh --tasks K --spp N --dir DIR -- [SCENE] [OPTIONS])" >&2; exit 2 ;;
  esac
done
if [ -z "$tasks" ] || [ -z "$spp" ] || [ -z "$dir" ]; then
  echo "submit.sh: --tasks, --spp and --dir are required" >&2
  exit 2
fi
if ! [[ $tasks =~ ^[1-9][0-9]*$ && $spp =~ ^[1-9][0-9]*$ ]] || ((tasks > spp)); then
  echo "submit.sh: --tasks K and --spp N must be whole numbers with 1 ≤ K ≤ N" >&2
  exit 2
fi
mkdir -p "$dir/logs"
dir=$(cd "$dir" && pwd)
export FURNACE_TASKS=$tasks FURNACE_SPP=$spp FURNACE_DIR=$dir
# shellcheck disable=SC2086 # the options are words
array=$(sbatch --parsable --export=ALL $sbatch_opts --array="0-$((tasks - 1))" \
  --output="$dir/logs/part-%a.out" "$here/render-part.sbatch" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable --export=ALL $sbatch_opts --dependency="afterany:$array" \
  --output="$dir/logs/merge.out" "$here/merge.sbatch" $merge_opts)
echo "$array ${merge%%;*}"

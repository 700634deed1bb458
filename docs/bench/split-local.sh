#!/usr/bin/env bash
# Split renders on this machine: one run against a 4-way split of the same samples (run one
# after the other, and as a 4-task Slurm array on a local one-node cluster), and the cost of
# merging a 4K film. Needs a release build (cargo build --release -p furnace-cli) and, for the
# Slurm part, root with slurm-wlm and munge. Usage: bash docs/bench/split-local.sh [WORKDIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
repo=$(pwd)
furnace=$repo/target/release/furnace
work=${1:-/tmp/furnace-split-bench}
rm -rf "$work"
mkdir -p "$work"
cd "$work"
t() { /usr/bin/time -f "%e s wall, %U s user, %M KiB max RSS" "$@"; }
scene=(--backend cpu --width 512 --height 512 --bounces 4 --sampler sobol)
spp=256
echo "== one run: built-in Cornell box 512², $spp spp, 4 bounces, CPU ($(nproc) cores)"
t "$furnace" render "${scene[@]}" --spp $spp --out single --quiet
echo "== the same samples as 4 parts, one after the other"
start=$(date +%s.%N)
for k in 0 1 2 3; do
  t "$furnace" render "${scene[@]}" --spp $spp --samples "$((k * spp / 4))..$(((k + 1) * spp / 4))" \
    --out "part-$k" --quiet
done
t "$furnace" merge part-0.exr part-1.exr part-2.exr part-3.exr -o merged --quiet
echo "parts + merge: $(echo "$(date +%s.%N) - $start" | bc) s"
"$furnace" compare merged.exr single.exr | grep -E "RMSE|relative MSE"

if command -v slurmctld >/dev/null && [ "$(id -u)" = 0 ]; then
  echo "== the same as a 4-task Slurm array (1 CPU per task, $(nproc) at once) and its merge job"
  trap '"$repo/slurm/local-cluster.sh" stop "$work/cluster"' EXIT
  eval "$("$repo/slurm/local-cluster.sh" start "$work/cluster")"
  export FURNACE_BIN=$furnace
  start=$(date +%s.%N)
  read -r _ merge < <("$repo/slurm/submit.sh" --tasks 4 --spp $spp --dir "$work/slurm" -- "${scene[@]}")
  while [ -n "$(squeue -h -j "$merge" 2>/dev/null)" ]; do sleep 0.2; done
  echo "submit → merged: $(echo "$(date +%s.%N) - $start" | bc) s"
  grep -h "backend:" "$work"/slurm/logs/part-*.out || true
  "$furnace" compare "$work/slurm/merged.exr" single.exr | grep -E "relative MSE"
fi

echo "== merging a 4K film (3840×2160) from 4 parts of 1 spp"
for k in 0 1 2 3; do
  "$furnace" render --backend cpu --width 3840 --height 2160 --bounces 1 --spp 4 --samples "$k..$((k + 1))" \
    --out "k4-$k" --quiet
done
ls -l k4-0.exr
t "$furnace" merge k4-0.exr k4-1.exr k4-2.exr k4-3.exr -o k4-merged
t "$furnace" merge k4-0.exr k4-1.exr -o k4-two --quiet --allow-gaps

#!/usr/bin/env bash
# The Slurm test of split renders (CI runs it; needs root, slurm-wlm and munge):
#
#   FURNACE_BIN=target/debug/furnace bash slurm/test.sh
#
# starts a one-node cluster on this machine (slurm/local-cluster.sh) and, through
# slurm/submit.sh, renders the built-in Cornell box as a 4-task job array twice:
#  A. task 1 is requeued (`scontrol requeue`) while it renders, after its first checkpoint: it
#     saves on SIGTERM, starts again, resumes its part, and the merge must equal a single run of
#     the same samples — relative MSE ≤ 1e-13 between the two EXRs' f32 images: one f32 ulp
#     (2⁻²³ relative) on every value would give 1.4e-14, and the f64 films differ by far less
#     (`furnace_render::split::merge_bound`); a wrong or missing sample range gives ≥ 1e-4;
#  B. task 2 is cancelled for good (`scancel`) while it renders: the merge job (afterany) must
#     fail, name task 2's missing samples, and write nothing.
# Logs, parts and images stay in target/test-output/slurm/ (printed on failure).
set -euo pipefail
cd "$(dirname "$0")/.."
furnace=$(realpath "${FURNACE_BIN:-target/debug/furnace}")
if [ ! -x "$furnace" ]; then
  echo "slurm test: no furnace binary at $furnace (build it, or set FURNACE_BIN)" >&2
  exit 1
fi
out=$(pwd)/target/test-output/slurm
rm -rf "$out"
mkdir -p "$out"
cluster=$out/cluster
trap 'slurm/local-cluster.sh stop "$cluster"' EXIT
eval "$(slurm/local-cluster.sh start "$cluster")"
export FURNACE_BIN=$furnace FURNACE_CHECKPOINT=1
# About 5 s of rendering per task on one core of the 2-core CI machine (the test-profile build):
# time for task 1 to write a checkpoint (after 1 s) and be requeued before it ends.
spp=3072
render=(--backend cpu --width 64 --height 64 --bounces 4 --sampler sobol --seed 7)

fail() {
  echo "slurm test FAILED: $*" >&2
  for f in "$out"/*/logs/*.out "$cluster"/slurmctld.log; do
    [ -f "$f" ] && { echo "--- $f" >&2; tail -n 30 "$f" >&2; }
  done
  exit 1
}
# Waits (at most $2 seconds) until the command $1 succeeds.
wait_until() {
  local deadline=$((SECONDS + $2))
  until eval "$1"; do
    ((SECONDS < deadline)) || fail "timed out after $2 s waiting for: $1"
    sleep 0.2
  done
}
state() { squeue -h -j "$1" -o %T 2>/dev/null || true; }
gone() { [ -z "$(state "$1")" ]; }
exit_code() { scontrol show job "$1" | sed -n 's/.*ExitCode=\([0-9]*:[0-9]*\).*/\1/p' | head -n 1; }

# --- A: a task requeued midway resumes, and the merge equals one run ---------------------------
read -r array merge < <(slurm/submit.sh --tasks 4 --spp $spp --dir "$out/a" -- "${render[@]}")
wait_until "[ -f '$out/a/part-1.exr' ] && [ \"\$(state ${array}_1)\" = RUNNING ]" 120
scontrol requeue "${array}_1"
t0=$SECONDS
wait_until "gone $merge" 300
echo "A: the array and its merge took $((SECONDS - t0)) s after the requeue"
[ "$(exit_code "$merge")" = 0:0 ] || fail "A: the merge job failed ($(exit_code "$merge"))"
grep -q "resumes $out/a/part-1.exr" "$out/a/logs/part-1.out" || fail "A: task 1 did not resume its part"
grep -q "resumed at" "$out/a/logs/part-1.out" || fail "A: furnace did not continue task 1's saved samples"
"$furnace" render "${render[@]}" --spp $spp --out "$out/single" --quiet
"$furnace" compare "$out/a/merged.exr" "$out/single.exr" | tee "$out/a/compare.txt"
relmse=$(awk '/^relative MSE/ {print $3}' "$out/a/compare.txt")
awk -v x="$relmse" 'BEGIN { exit !(x <= 1e-13) }' || fail "A: merged vs single run: relative MSE $relmse > 1e-13"

# --- B: a task cancelled for good: the merge refuses, naming the missing samples ---------------
read -r array merge < <(slurm/submit.sh --tasks 4 --spp $spp --dir "$out/b" -- "${render[@]}")
wait_until "[ -f '$out/b/part-2.exr' ] && [ \"\$(state ${array}_2)\" = RUNNING ]" 120
scancel "${array}_2"
wait_until "gone $merge" 300
[ "$(exit_code "$merge")" != 0:0 ] || fail "B: the merge succeeded without task 2's samples"
grep -q "samples missing from the $spp-sample render: samples [0-9]*\.\.2304 (part $out/b/part-2.exr (1536..2304) stopped at sample" \
  "$out/b/logs/merge.out" || fail "B: the merge did not name task 2's missing samples"
[ ! -e "$out/b/merged.exr" ] || fail "B: the refused merge wrote $out/b/merged.exr"
echo "slurm test passed: requeued task resumed, merge equal to one run (relative MSE $relmse); cancelled task named"

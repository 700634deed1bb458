#!/usr/bin/env bash
# furnace's CPU integrator, Mitsuba 3 (llvm_ad_rgb) and Blender Cycles (CPU), back to back on this
# machine, on each reference scene of ../shared/references: the same size, bounce count and
# samples per pixel; for each, Msamples/s and the error against the scene's 65 536-spp reference.
#
#   FURNACE=target/release/furnace bash docs/bench/cpu-peers.sh
#
# FURNACE    the furnace binary (default target/release/furnace)
# SCENES     reference scenes (default: all eight; names as in ../shared/references/README.md), or
#            lit_room_20152: make_interior.py's light-heavy room (--lamps), with no reference in
#            ../shared: Mitsuba's of REF_SPP (default 4096) samples is made once at the render's
#            size into REFS (default .dev/refs); its size in the file is 1920×1440, DIV=6 is 320×240
# FURNACE_FLAGS  more flags for furnace's render (e.g. "--light-selection power")
# SPP        samples per pixel for every renderer (default 64)
# DIV        render at the reference's size / DIV (default 1; DIV=4 is a quick end-to-end check:
#            the reference is then averaged over DIV×DIV blocks)
# ROUNDS     rounds of the three renderers per scene (default 1)
# SAMPLER    furnace's sampler (default sobol, furnace's default; random = Mitsuba's independent)
# ONLY       renderers to run (default "furnace mitsuba cycles")
# SHARED     the shared folder holding oracle/ and references/ (default ../shared)
# BPY_PYTHON a Python with the `bpy` 5.0 module (default /work/wt/bpy-venv/bin/python; made by
#            `python3 -m venv DIR && DIR/bin/pip install 'bpy==5.0.*'`, Python 3.11)
# MITSUBA_AVX2=1 also runs Mitsuba with its JIT compiling for AVX2, 8 lanes (mitsuba_avx2.py):
#            on an AVX-512 machine, what Mitsuba does on an AVX2 one, on the same cores
# WAIT_IDLE  seconds Mitsuba's script waits for an idle machine before timing (default 5)
#
# Settings: furnace `render --backend cpu --masking separable --compensation off` (the
# references' material model), the rate from its summary line (the render passes' time);
# Mitsuba through the oracle's render_ref.py (its JIT warm-up excluded, passes of ≤ 64 spp,
# max_depth = bounces + 1, path or volpath as the scene says); Cycles through cycles_render.py
# (the glTF importer, the references' conventions; the time of SPP samples less that of 1).
# The error is score.py's (the oracle's compare.py): RMSE, relative MSE and the image mean's
# ratio to the reference's per channel. The oracle needs `bash ../shared/oracle/setup.sh` once.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
shared=$(cd "${SHARED:-$root/../shared}" && pwd)
furnace=$(realpath "${FURNACE:-$root/target/release/furnace}")
bpy_python=${BPY_PYTHON:-/work/wt/bpy-venv/bin/python}
refs=${REFS:-$root/.dev/refs}
spp=${SPP:-64}
div=${DIV:-1}
only=" ${ONLY:-furnace mitsuba cycles} "
scenes=${SCENES:-cbox cbox_area cbox_many_lights cbox_point cbox_sun_disc envmap_spheres glass_box glass_absorb}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# shellcheck source=/dev/null
. "$shared/oracle/env.sh"
export ORACLE=$shared/oracle
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores," \
  "load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "furnace: $furnace ($("$furnace" --version 2>/dev/null | head -1))"
echo "SPP=$spp DIV=$div SAMPLER=${SAMPLER:-sobol}"
echo
echo "| scene | size | bounces | renderer | Msamples/s | RMSE | relative MSE | mean ratio R, G, B |"
echo "|---|---|---|---|---|---|---|---|"

# score NAME RENDERER RATE IMAGE: one table row.
score() {
  local s=$1 who=$2 rate=$3 image=$4
  python "$root/docs/bench/score.py" "$image" "$ref.exr" "${ref}_stderr.exr" > "$work/score.json"
  python - "$work/score.json" "$s" "${w}x$h" "$bounces" "$who" "$rate" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
s, size, b, who, rate = sys.argv[2:]
if "error" in d:
    print(f"| {s} | {size} | {b} | {who} | {rate} | {d['error']} | | |")
else:
    ratio = ", ".join(f"{r:.4f}" for r in d["mean_ratio_rgb"])
    print(f"| {s} | {size} | {b} | {who} | {rate} | {d['rmse']:.4g} | {d['rel_mse']:.4g} | {ratio} |")
EOF
}

for s in $scenes; do
  case $s in
    cbox) dir=cbox ;;
    envmap_spheres) dir=envmap ;;
    glass_*) dir=glass ;;
    lit_room_*) dir= ;;
    *) dir=lights ;;
  esac
  if [ -z "$dir" ]; then
    # make_interior.py's target of 2·10⁴ triangles gives lit_room_20152.
    python "$root/docs/device/make_interior.py" "$work" 2e4 --lamps > /dev/null
    [ -f "$work/$s.gltf" ] || { echo "$s: make_interior.py wrote $(ls "$work"/lit_room_*.gltf)"; exit 1; }
  else
    cp "$shared/references/$dir/$s".* "$work/"
  fi
  if [ "$s" = envmap_spheres ]; then cp "$shared/references/envmap/${s}_env.exr" "$work/"; fi
  read -r w0 h0 bounces < <(python -c "import json; r = json.load(open('$work/$s.gltf'))['scenes'][0]['extras']['render']; print(r['width'], r['height'], r['max_bounces_equivalent'])")
  w=$((w0 / div)); h=$((h0 / div))
  ref=$shared/references/$dir/${s}_ref_bounces$bounces
  if [ -z "$dir" ]; then
    # No reference in ../shared: Mitsuba's, made here once at this size (REF_SPP samples).
    ref=$refs/${s}_ref_bounces${bounces}_${w}x$h
    if [ ! -f "$ref.exr" ]; then
      mkdir -p "$refs"
      ORACLE_SCENES=$work ORACLE_OUT=$work ORACLE_RESULTS=$work ORACLE_SIZE=${w}x$h WAIT_IDLE=0 \
        python "$shared/oracle/render_ref.py" "$s" llvm_ad_rgb 64 $((${REF_SPP:-4096} / 64)) \
        --max-depth=$((bounces + 1)) > "$work/reference.log" 2>&1 || { tail -3 "$work/reference.log"; exit 1; }
      made=$work/${s}_maxdepth$((bounces + 1))_llvm_ad_rgb_${REF_SPP:-4096}spp
      cp "$made.exr" "$ref.exr"; cp "${made}_stderr.exr" "${ref}_stderr.exr"
    fi
  fi
  for round in $(seq "${ROUNDS:-1}"); do
    if [[ $only == *" furnace "* ]]; then
      # shellcheck disable=SC2086
      "$furnace" render "$work/$s.gltf" --backend cpu --width "$w" --height "$h" --spp "$spp" \
        --bounces "$bounces" --sampler "${SAMPLER:-sobol}" --masking separable --compensation off \
        ${FURNACE_FLAGS:-} --out "$work/furnace" > "$work/furnace.log" 2>&1 || { tail -3 "$work/furnace.log"; exit 1; }
      rate=$(grep -oE '[0-9.]+ Msamples/s\)' "$work/furnace.log" | tail -1 | cut -d' ' -f1)
      score "$s" "furnace CPU (${SAMPLER:-sobol}${FURNACE_FLAGS:+ $FURNACE_FLAGS})" "$rate" "$work/furnace.exr"
    fi
    if [[ $only == *" mitsuba "* ]]; then
      # Mitsuba renders passes of at most 64 spp: the largest such divisor of SPP.
      per_pass=64; while [ $((spp % per_pass)) != 0 ]; do per_pass=$((per_pass - 1)); done
      rm -f "$work"/*_llvm_ad_rgb_*
      ORACLE_SCENES=$work ORACLE_OUT=$work ORACLE_RESULTS=$work ORACLE_SIZE=${w}x$h \
        WAIT_IDLE=${WAIT_IDLE:-5} python "$shared/oracle/render_ref.py" "$s" llvm_ad_rgb "$per_pass" \
        $((spp / per_pass)) --max-depth=$((bounces + 1)) > "$work/mitsuba.log" 2>&1 \
        || { tail -3 "$work/mitsuba.log"; exit 1; }
      tag=${s}_maxdepth$((bounces + 1))_llvm_ad_rgb_${spp}spp
      rate=$(python -c "import json; print('%.3f' % json.load(open('$work/$tag.json'))['Msamples_per_s'])")
      score "$s" "Mitsuba llvm_ad_rgb" "$rate" "$work/$tag.exr"
      if [ -n "${MITSUBA_AVX2:-}" ]; then
        rm -f "$work"/*_llvm_ad_rgb_*
        ORACLE_SCENES=$work ORACLE_OUT=$work ORACLE_RESULTS=$work ORACLE_SIZE=${w}x$h \
          WAIT_IDLE=${WAIT_IDLE:-5} python "$root/docs/bench/mitsuba_avx2.py" "$shared/oracle/render_ref.py" \
          "$s" llvm_ad_rgb "$per_pass" $((spp / per_pass)) --max-depth=$((bounces + 1)) > "$work/mitsuba.log" 2>&1 \
          || { tail -3 "$work/mitsuba.log"; exit 1; }
        rate=$(python -c "import json; print('%.3f' % json.load(open('$work/$tag.json'))['Msamples_per_s'])")
        score "$s" "Mitsuba llvm_ad_rgb, AVX2 ×8" "$rate" "$work/$tag.exr"
      fi
    fi
    if [[ $only == *" cycles "* ]]; then
      "$bpy_python" "$root/docs/bench/cycles_render.py" "$work/$s.gltf" "$work/cycles.exr" \
        "$w" "$h" "$spp" "$bounces" > "$work/cycles.log" 2>&1 || { tail -3 "$work/cycles.log"; exit 1; }
      rate=$(tail -1 "$work/cycles.log" | python -c "import json, sys; print('%.3f' % json.load(sys.stdin)['Msamples_per_s'])")
      score "$s" "Cycles $(tail -1 "$work/cycles.log" | python -c "import json, sys; print(json.load(sys.stdin)['blender'])") CPU" "$rate" "$work/cycles.exr"
    fi
  done
done

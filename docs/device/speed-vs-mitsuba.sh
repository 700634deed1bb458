#!/bin/bash
# GPU speed: furnace binaries interleaved with Mitsuba 3 (cuda_ad_rgb) at equal samples on each
# reference scene, one device command; prints a Markdown table.
#
#   bash docs/device/speed-vs-mitsuba.sh .dev/furnace-a.xz [.dev/furnace-b.xz ...]
#
# Per scene, Mitsuba renders SPP samples per pixel (passes of 64) twice and the second is quoted
# (the first runs while the GPU's clocks rise); then ROUNDS rounds in which every binary runs
# `furnace bench --backend gpu --spp SPP --no-rays` in turn. The last column is the first
# binary's median over Mitsuba's, and with two binaries or more each one's median over the first
# binary's: the before/after check of a change (the same samples: expect ±1 %).
#
# SCENES   names among: cbox256 cbox cbox_area cbox_many_lights cbox_point cbox_sun_disc
#          envmap_spheres glass_box glass_absorb interior lit_room (default: all but the two rooms,
#          which need .dev/sc/interior_19880.* and .dev/sc/lit_room_20152.* from make_interior.py,
#          the second with --lamps)
# SPP (256), ROUNDS (3), SAMPLER (random: Mitsuba's independent sampler; sobol is furnace's
# default), WIDTH x HEIGHT (1920 x 1080; cbox256 is 256², the interior 1920 x 1440 at 6 bounces),
# MITSUBA=0 skips Mitsuba.
# Needs .gl/, the binaries, and for Mitsuba .mi/ (or MITSUBA_SITE) and .dev/oracle/ (README.md);
# Mitsuba's cbox needs .dev/sc/cbox.{gltf,bin} from ../shared/references/cbox.
set -u
source docs/device/env.sh
args=("$@")
unpack "$@"
[ ${#bins[@]} -gt 0 ] || { echo "usage: $0 FURNACE.xz [FURNACE.xz ...]"; exit 2; }
mi_ok=0
if [ "${MITSUBA:-1}" != 0 ] && mitsuba_setup; then mi_ok=1; fi
w=${WIDTH:-1920}; h=${HEIGHT:-1080}; spp=${SPP:-256}; sampler=${SAMPLER:-random}
# name | furnace scene | Mitsuba scene | WxH | bounces
configs=("cbox256|cbox|cbox|256x256|4" "cbox|cbox|cbox|${w}x$h|4"
  "cbox_area|$SC/cbox_area.gltf|cbox_area|${w}x$h|4" "cbox_many_lights|$SC/cbox_many_lights.gltf|cbox_many_lights|${w}x$h|4"
  "cbox_point|$SC/cbox_point.gltf|cbox_point|${w}x$h|4" "cbox_sun_disc|$SC/cbox_sun_disc.gltf|cbox_sun_disc|${w}x$h|4"
  "envmap_spheres|$SC/envmap_spheres.gltf|envmap_spheres|${w}x$h|4"
  "glass_box|$SC/glass_box.gltf|glass_box|${w}x$h|8" "glass_absorb|$SC/glass_absorb.gltf|glass_absorb|${w}x$h|8"
  "interior|$SC/interior_19880.gltf|interior_19880|1920x1440|6"
  "lit_room|$SC/lit_room_20152.gltf|lit_room_20152|1920x1440|6")
want=" ${SCENES:-cbox256 cbox cbox_area cbox_many_lights cbox_point cbox_sun_disc envmap_spheres glass_box glass_absorb} "
rows=/tmp/rows.txt; : > $rows
for c in "${configs[@]}"; do
  IFS='|' read -r name scene mscene size b <<< "$c"
  [[ $want == *" $name "* ]] || continue
  mrate=-
  if [ $mi_ok = 1 ]; then
    # Mitsuba renders passes of at most 64 spp: the largest such divisor of SPP.
    per_pass=64; while [ $((spp % per_pass)) != 0 ]; do per_pass=$((per_pass - 1)); done
    mitsuba "$mscene" "$size" $per_pass $((spp / per_pass)) --max-depth=$((b + 1)) > /dev/null
    mrate=$(mitsuba "$mscene" "$size" $per_pass $((spp / per_pass)) --max-depth=$((b + 1)))
  fi
  echo "$name $size $b bounces: Mitsuba $mrate"
  line="$name|$size|$b|$mrate"
  for k in "${!bins[@]}"; do rates[$k]=""; done
  for round in $(seq "${ROUNDS:-3}"); do
    for k in "${!bins[@]}"; do
      "${bins[$k]}" bench --backend gpu --scene "$scene" --width "${size%x*}" --height "${size#*x}" \
        --bounces "$b" --sampler "$sampler" --spp "$spp" --no-rays -q --json /tmp/b.json > /tmp/b.log 2>&1 \
        || tail -2 /tmp/b.log
      r=$(python3 -c "import json; print('%.1f' % json.load(open('/tmp/b.json'))['msamples_per_s'])" 2> /dev/null || echo nan)
      echo "  round $round, binary $((k + 1)) (${args[$k]}): $r"
      rates[$k]="${rates[$k]} $r"
    done
  done
  for k in "${!bins[@]}"; do line="$line|${rates[$k]# }"; done
  echo "$line" >> $rows
done
echo
echo "furnace: $*; $sampler sampler, $spp spp, \`furnace bench --backend gpu --no-rays\`; Mitsuba 3 cuda_ad_rgb, the second of two renders; Msamples/s"
echo
python3 - "$rows" "${#bins[@]}" <<'PY'
import statistics, sys
rows, n = sys.argv[1], int(sys.argv[2])
head = ["scene", "size", "bounces", "Mitsuba"] + [f"furnace {k + 1}" for k in range(n)] + ["furnace 1 / Mitsuba"]
head += [f"{k + 1} / 1" for k in range(1, n)]
print("| " + " | ".join(head) + " |")
print("|" + "---|" * len(head))
for row in open(rows):
    f = row.strip().split("|")
    runs = [[float(x) for x in r.split()] for r in f[4:]]
    med = [statistics.median(r) if r else float("nan") for r in runs]
    cells = f[:4] + [", ".join(f"{x:.1f}" for x in r) for r in runs]
    cells.append(f"**{med[0] / float(f[3]):.2f}×**" if f[3] not in ("-", "") else "—")
    cells += [f"{m / med[0]:.3f}" for m in med[1:]]
    print("| " + " | ".join(cells) + " |")
PY

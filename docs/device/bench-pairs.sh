#!/bin/bash
# GPU speed of several furnace binaries on glTF scenes, interleaved in one device command: the
# before/after check of a change on scenes speed-vs-mitsuba.sh lacks (textured assets), or a
# short one when little device time is left. Prints one line per run and a median table.
#
#   SCENES="/tmp/sc/cbox_area.gltf tests/data/scenes/DamagedHelmet/glTF-Binary/DamagedHelmet.glb" \
#     bash docs/device/bench-pairs.sh .dev/furnace-before.xz .dev/furnace-after.xz
#
# SCENES   glTF files (/tmp/sc/ holds the reference scenes once env.sh has run; default: cbox_area,
#          envmap_spheres and DamagedHelmet)
# ROUNDS (3), SPP (128), WIDTH x HEIGHT (1920 x 1080), BOUNCES (4).
set -u
source "$(dirname "$0")/env.sh"
unpack "$@"
scenes=${SCENES:-"$SC/cbox_area.gltf $SC/envmap_spheres.gltf tests/data/scenes/DamagedHelmet/glTF-Binary/DamagedHelmet.glb"}
out=$(mktemp)
for s in $scenes; do
  for round in $(seq "${ROUNDS:-3}"); do
    for k in "${!bins[@]}"; do
      timeout 120 "${bins[$k]}" bench --backend gpu --scene "$s" --width "${WIDTH:-1920}" --height "${HEIGHT:-1080}" \
        --bounces "${BOUNCES:-4}" --spp "${SPP:-128}" --no-rays -q --json /tmp/b.json > /tmp/b.log 2>&1 || tail -2 /tmp/b.log
      rate=$(python3 -c "import json; print('%.1f' % json.load(open('/tmp/b.json'))['msamples_per_s'])")
      echo "$(basename "$s") round $round binary $((k + 1)) ($(basename "${@:$((k + 1)):1}")): $rate"
      echo "$(basename "$s") $k $rate" >> "$out"
    done
  done
done
python3 - "$out" "$@" <<'PY'
import statistics, sys
rows = {}
for line in open(sys.argv[1]):
    scene, k, rate = line.split()
    rows.setdefault(scene, {}).setdefault(int(k), []).append(float(rate))
names = sys.argv[2:]
print("| scene | " + " | ".join(names) + " | each / first |")
print("|---|" + "---|" * (len(names) + 1))
for scene, by in rows.items():
    med = [statistics.median(by[k]) for k in sorted(by)]
    print(f"| {scene} | " + " | ".join(f"{m:.1f}" for m in med) + " | " + " ".join(f"{m / med[0]:.3f}" for m in med[1:]) + " |")
PY

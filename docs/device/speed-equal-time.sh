#!/bin/bash
# Equal-time error against Mitsuba 3 (cuda_ad_rgb) at the references' 256² (320×240 for the
# environment map's): Mitsuba's RMSE after 16..1024 spp (one pass each, its render_s), furnace's
# error-vs-time curve (`furnace chart`, GPU) per configuration, and for each Mitsuba point
# furnace's RMSE after the same seconds (log-log interpolation) and the time furnace needs for
# Mitsuba's RMSE. Inputs as speed-ab.sh (Mitsuba unpacked to /root/site by a first command).
xz -dc .dev/furnace-new.xz > /tmp/fn; chmod +x /tmp/fn
source docs/device/speed-env.sh
for v in "cbox|$R/cbox/cbox_ref_bounces4.exr|" "cbox_area|$R/lights/cbox_area_ref_bounces4.exr|--light-selection power,bvh" \
         "cbox_many_lights|$R/lights/cbox_many_lights_ref_bounces4.exr|--light-selection power,bvh" \
         "envmap_spheres|$R/envmap/envmap_spheres_ref_bounces4.exr|" \
         "cbox_point|$R/lights/cbox_point_ref_bounces4.exr|" "cbox_sun_disc|$R/lights/cbox_sun_disc_ref_bounces4.exr|"; do
  IFS='|' read -r s ref opts <<< "$v"
  # SCENES="a b": only those.
  if [ -n "$SCENES" ] && [[ " $SCENES " != *" $s "* ]]; then continue; fi
  size=$(python3 -c "import json; d=json.load(open('/tmp/sc/$s.gltf'))['scenes'][0]['extras']['render']; print(f\"{d['width']}x{d['height']}\")")
  echo "label,spp,seconds,rmse,relmse" > $W/mitsuba_$s.csv
  for spp in 16 64 256 1024; do
    ORACLE_SIZE=$size mi $s cuda_ad_rgb $spp 1
    t=$(python3 -c "import json; print(json.load(open('/tmp/mr/${s}_cuda_ad_rgb_${spp}spp.json'))['render_s'])")
    /tmp/fn compare /tmp/mo/${s}_cuda_ad_rgb_${spp}spp.exr $ref > /tmp/cmp.txt
    echo "mitsuba cuda_ad_rgb,$spp,$t,$(awk '/^RMSE/{print $2}' /tmp/cmp.txt),$(awk '/^relative MSE/{print $3}' /tmp/cmp.txt)" >> $W/mitsuba_$s.csv
  done
  /tmp/fn chart --reference $ref --scene /tmp/sc/$s.gltf --masking separable --compensation off --samplers sobol,random \
    --sampling caps $opts --spp 1024 --backends gpu --external $W/mitsuba_$s.csv --out $W/chart_$s -q > $W/chart_$s.log 2>&1 || tail -3 $W/chart_$s.log
  python3 - $W/chart_$s/chart.csv $W/mitsuba_$s.csv $s <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
mi = list(csv.DictReader(open(sys.argv[2])))
configs = {}
for r in rows:
    configs.setdefault(r["config"], []).append((float(r["seconds"]), float(r["rmse"])))
def interp(curve, x, key):  # log-log interpolation of (seconds, rmse) along `key` (0: by time, 1: by error)
    pts = sorted(curve, key=lambda p: p[key] if key == 0 else -p[1])
    for a, b in zip(pts, pts[1:]):
        if (key == 0 and a[0] <= x <= b[0]) or (key == 1 and b[1] <= x <= a[1]):
            f = (math.log(x) - math.log(a[key])) / (math.log(b[key]) - math.log(a[key]))
            return math.exp(math.log(a[1 - key]) + f * (math.log(b[1 - key]) - math.log(a[1 - key])))
    return float("nan")
print(f"== {sys.argv[3]}: Mitsuba points; furnace RMSE at Mitsuba's seconds (ratio Mitsuba/furnace); furnace seconds to Mitsuba's RMSE (speed-up)")
for m in mi:
    t, e = float(m["seconds"]), float(m["rmse"])
    line = f"mitsuba {m['spp']:>5} spp {t:.4f} s rmse {e:.5f} |"
    for c, curve in configs.items():
        ef = interp(curve, t, 0)
        tf = interp(curve, e, 1)
        line += f" {c}: {ef:.5f} ({e / ef:.2f}x) {tf:.4f} s ({t / tf:.2f}x) |"
    print(line)
PY
done
tar -czf $OUT/results.tgz -C $W . 2>/dev/null

#!/bin/bash
# The BVH build preset for small scenes on the H200: the head's choice (obvhs `Slow` up to
# 300 000 triangles) against `VerySlow` (reinsertion on every node), interleaved, 2 rounds,
# random sampler, with the time to first frame. Inputs as speed-ab.sh, with
# .dev/furnace-new.xz (the head) and .dev/furnace-vs.xz (the head with
# `BuildQuality::for_triangle_count` returning VerySlow where it returns Slow).
for b in new vs; do xz -dc .dev/furnace-$b.xz > /tmp/f$b; chmod +x /tmp/f$b; done
source docs/device/speed-env.sh
for round in 1 2; do for sc in "${scenes[@]}"; do for b in new vs; do
  /tmp/f$b bench --backend gpu ${sc#*|} --sampler random --min-seconds 1.5 --no-rays -q --json $W/b.json > $W/b.log 2>&1 || tail -2 $W/b.log
  python3 -c "import json; d=json.load(open('$W/b.json')); print('${sc%%|*} $b $round', round(d['msamples_per_s'],1), 'Ms/s, first frame', round(d['time_to_first_frame_s'],3), 's')"
done; done; done
echo "== larger procedural interiors (VerySlow up to 300 000 triangles in vs, Medium above in both)"
for n in 1e5 3e5; do for b in new vs new vs; do
  /tmp/f$b bench --backend gpu --scene interior:$n --width 1920 --height 1080 --sampler random --min-seconds 1.5 --no-rays -q --json $W/b.json > $W/b.log 2>&1 || tail -2 $W/b.log
  python3 -c "import json; d=json.load(open('$W/b.json')); print('interior:$n $b', d['triangles'], 'triangles', round(d['msamples_per_s'],1), 'Ms/s, first frame', round(d['time_to_first_frame_s'],3), 's')"
done; done
if [ -d /root/site/mitsuba ]; then
  echo "== Mitsuba and furnace at equal samples, random sampler (the interior and the box)"
  for v in "${equal[@]}"; do
    IFS='|' read -r s size path spp passes b <<< "$v"
    case $s in interior_19880|cbox) ;; *) continue;; esac
    mitsuba_at $s $size $spp $passes
    for bin in new vs; do
      /tmp/f$bin bench --backend gpu --scene $path --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --spp $((spp*passes)) --no-rays -q --json $W/b.json > $W/b.log 2>&1 || tail -2 $W/b.log
      python3 -c "import json; d=json.load(open('$W/b.json')); print('furnace $s $size $bin', round(d['msamples_per_s'],1), 'Ms/s')"
    done
  done
fi

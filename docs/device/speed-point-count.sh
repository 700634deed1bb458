#!/bin/bash
# Where one point light per event starts to pay at equal time: boxes with N = 2, 4, 5, 8, 16, 32
# point lights (cbox_point's two, then N − 2 dim ones under the ceiling, as speed-point-one.sh
# writes them), 256², 4 bounces. Per N: a reference of the same scene by furnace itself
# (`all`, 8192 spp Owen-Sobol), then for `all` and `one` the RMSE after 256 spp (random sampler:
# its error falls as 1/√N, so MSE × seconds is a figure of merit) and the rate (furnace bench);
# efficiency = 1 / (MSE × seconds per sample). Needs .gl/, .dev/furnace-new.xz, .dev/sc/.
xz -dc .dev/furnace-new.xz > /tmp/fn; chmod +x /tmp/fn
source docs/device/speed-env.sh
for n in 2 4 5 8 16 32; do
  python3 - $n <<'PY'
import json, sys
n = int(sys.argv[1])
g = json.load(open('/tmp/sc/cbox_point.gltf'))
lights = g['extensions']['KHR_lights_punctual']['lights']
scene = g['scenes'][0]
for i in range(n - 2):
    x, z = -0.8 + 0.4 * (i % 5), -0.75 + 0.3 * (i // 5)
    lights.append({'name': f'dim{i}', 'type': 'point', 'intensity': 0.02 + 0.01 * (i % 7),
                   'color': [0.6 + 0.4 * ((i * 3) % 5) / 4, 0.7, 0.6 + 0.4 * ((i * 2) % 5) / 4]})
    g['nodes'].append({'name': f'dim{i}', 'translation': [x, 1.55, z],
                       'extensions': {'KHR_lights_punctual': {'light': len(lights) - 1}}})
    scene['nodes'].append(len(g['nodes']) - 1)
json.dump(g, open(f'/tmp/sc/cbox_pointn{n}.gltf', 'w'))
PY
  s=/tmp/sc/cbox_pointn$n.gltf
  /tmp/fn render $s --backend gpu --width 256 --height 256 --spp 8192 --out $W/ref$n.exr -q > /dev/null 2>&1
  for p in all one; do
    /tmp/fn render $s --backend gpu --width 256 --height 256 --sampler random --point-lights $p --spp 256 --out $W/p.exr -q > /dev/null 2>&1
    rmse=$(/tmp/fn compare $W/p.exr $W/ref$n.exr | awk '/^RMSE/{print $2}')
    bench "n$n $p" fn --scene $s --width 256 --height 256 --sampler random --point-lights $p --min-seconds 1 > $W/r.txt
    rate=$(awk '{print $3}' $W/r.txt)
    python3 -c "r=$rmse; m=$rate; print('N=$n $p: RMSE(256 spp) %.4e, %.1f Msamples/s, efficiency 1/(MSE*ns per sample) %.4g' % (r, m, 1/(r*r*1e3/m)))"
  done
done

#!/bin/bash
# Where one point light per event starts to pay at equal time: boxes with N = 2, 4, 5, 8, 16, 32
# point lights (cbox_point's two, then N − 2 dim ones under the ceiling, as make_point_box.py
# writes them), 256², 4 bounces. Per N: a reference of the same scene by furnace itself
# (`all`, 8192 spp Owen-Sobol), then for `all` and `one` the RMSE after 256 spp (random sampler:
# its error falls as 1/√N, so MSE × seconds is a figure of merit) and the rate (furnace bench);
# efficiency = 1 / (MSE × seconds per sample). Needs .gl/, .dev/furnace-new.xz, .dev/sc/.
xz -dc .dev/furnace-new.xz > /tmp/fn; chmod +x /tmp/fn
source docs/device/speed-env.sh
for n in 2 4 5 8 16 32; do
  python3 docs/device/make_point_box.py $n /tmp/sc/cbox_point.gltf /tmp/sc/cbox_pointn$n.gltf
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

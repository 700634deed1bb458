#!/bin/bash
# Invocations per pixel against path length, for a rule that picks one invocation per pixel
# (path regeneration) where paths are long: --group-samples 1, 2, 4 on the box and the interior
# at 4, 6 and 8 bounces, 1080p and 1440p. Needs .gl/, .dev/furnace-new.xz, .dev/sc/; no Mitsuba.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
echo "== invocations per pixel by path length, random sampler"
for scene in cbox $I; do for size in 1920x1080 1920x1440; do for b in 4 6 8; do for g in 1 2 4; do
  bench "$(basename $scene) $size b$b group $g" fnew --scene $scene --width ${size%x*} --height ${size#*x} --bounces $b --sampler random --min-seconds 1 --group-samples $g
done; done; done; done

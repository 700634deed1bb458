#!/usr/bin/env bash
# AOVs, adaptive sampling and denoising on the H200 machine (one device command): the cost of the
# AOVs on the GPU integrator, adaptive sampling's time and samples, Open Image Denoise's time on
# the host's CPU (16 cores) and on the H200 (OIDN's CUDA device), a 16k × 16k denoise, and the
# error-vs-spp / error-vs-time charts of raw, adaptive, denoised and adaptive + denoised renders
# against the Mitsuba references.
# Inputs (docs/device/README.md): .dev/furnace-new.xz, a stripped release `furnace` built with
# `--features denoise`; .dev/bench.xz, furnace-denoise's `bench` example; OIDN 2.5.1's libraries
# (libOpenImageDenoise*, _core, _device_cpu, _device_cuda, libtbb) as an xz tar, split in two
# (/root/oidn.part1 left by a first command, .dev/oidn.part2) to fit the 64 MiB transfer limit.
set -u
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
OIDN=/root/.cache/furnace/oidn-2.5.1
mkdir -p "$OIDN"
cat /root/oidn.part1 .dev/oidn.part2 | xz -d | tar -C "$OIDN" -xf -
export LD_LIBRARY_PATH=$OIDN/lib
xz -dc .dev/furnace-new.xz > /tmp/furnace && chmod +x /tmp/furnace
xz -dc .dev/bench.xz > /tmp/bench && chmod +x /tmp/bench
F=/tmp/furnace
W=$OUT
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
lscpu | grep -E "Model name|^CPU\(s\)"

echo "== AOVs: cbox 1920x1080, 256 spp, GPU (interleaved, 3 each)"
for i in 1 2 3; do
  $F render --backend gpu --width 1920 --height 1080 --spp 256 --out /tmp/plain 2>&1 | grep "Msamples/s"
  $F render --backend gpu --width 1920 --height 1080 --spp 256 --aovs --out /tmp/aovs 2>&1 | grep "Msamples/s"
done

echo "== adaptive sampling: cbox 1920x1080, up to 1024 spp, GPU"
$F render --backend gpu --width 1920 --height 1080 --spp 1024 --out /tmp/a0 2>&1 | grep -E "Msamples/s"
for t in 0.05 0.02 0.01; do
  $F render --backend gpu --width 1920 --height 1080 --spp 1024 --noise-threshold $t --out /tmp/a$t 2>&1 | grep -E "Msamples/s|adaptive"
done

echo "== render --denoise: cbox 16 spp, GPU render, OIDN on the CPU (16 cores) and CUDA"
for size in "1920 1080" "3840 2160"; do
  set -- $size
  for dev in cuda cpu; do
    /usr/bin/time -f "peak RSS %M KB, %e s wall" $F render --backend gpu --width $1 --height $2 --spp 16 --denoise --denoise-device $dev --out /tmp/d 2>&1 | grep -E "denoised on|peak RSS|Msamples"
  done
  $F render --backend gpu --width $1 --height $2 --spp 16 --denoise --denoise-device cuda --denoise-prefilter --out /tmp/dp 2>&1 | grep -E "denoised on"
done
$F render --backend gpu --width 1920 --height 1080 --spp 1 --denoise --denoise-device cuda --out $W/cbox_1spp 2>&1 | grep -E "denoised on"

echo "== OIDN bench (synthetic scene, 16-sample noise): CUDA and CPU, best of 3"
/tmp/bench cuda 3 default 512x512,1920x1080,3840x2160
/tmp/bench cpu 2 default 512x512,1920x1080,3840x2160
echo "== 16384 x 16384 (268 Mpixels), CUDA, once"
/usr/bin/time -f "peak RSS %M KB, %e s wall" /tmp/bench cuda 1 default 16384x16384 2>&1 | tail -6
nvidia-smi --query-gpu=memory.used --format=csv,noheader

echo "== charts: raw / adaptive / denoised against Mitsuba, GPU"
R=tests/data/references
$F chart --reference $R/cbox/cbox_ref_bounces4.exr --masking separable --compensation off --samplers sobol \
  --sampling caps --backends gpu --noise-threshold off,0.05,0.02 --denoise off,on --spp 1024 --out $W/chart_cbox -q \
  > $W/chart_cbox.log 2>&1 || tail -3 $W/chart_cbox.log
$F chart --reference $R/lights/cbox_area_ref_bounces4.exr --scene $R/lights/cbox_area.gltf --masking separable \
  --compensation off --samplers sobol --sampling caps --backends gpu --noise-threshold off,0.05,0.02 --denoise off,on \
  --spp 1024 --out $W/chart_area -q > $W/chart_area.log 2>&1 || tail -3 $W/chart_area.log
for c in cbox area; do cut -d, -f1,6,7,8,9,18 $W/chart_$c/chart.csv; done

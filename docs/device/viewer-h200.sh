#!/usr/bin/env bash
# The viewer's responsiveness on a GPU machine without a display: Xvfb (carried as Debian
# packages in .xv/, unpacked at /), the NVIDIA Vulkan driver, `furnace view` driven by a script
# that prints each frame's wall time. Also the same scenes' pass times from `furnace bench`.
# Run from the repository root on the device; .dev/furnace-new.xz is the stripped release binary.
set -u
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
# The X packages go to a prefix of their own (their libraries must not replace the machine's),
# except the keyboard data and compiler Xvfb looks for at fixed paths.
for f in .xv/*.deb; do dpkg -x "$f" /opt/xv; done
cp -rn /opt/xv/usr/share/X11 /usr/share/ 2>/dev/null; cp -n /opt/xv/usr/bin/xkbcomp /usr/bin/ 2>/dev/null
XLIB=/opt/xv/usr/lib/x86_64-linux-gnu:/opt/xv/lib/x86_64-linux-gnu
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
xz -dc .dev/furnace-new.xz > /tmp/furnace && chmod +x /tmp/furnace
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
LD_LIBRARY_PATH=$XLIB /opt/xv/usr/bin/Xvfb :5 -screen 0 2000x1200x24 -nolisten tcp > /tmp/xvfb.log 2>&1 &
sleep 2
export DISPLAY=:5
cat > /tmp/s.txt <<'S'
wait-seconds 4
print
drag left 120 0
wait-frames 1
print
drag left 2 0
drag left 2 0
wait-frames 20
print
hold w 1.0
print
wait-seconds 4
print
save /tmp/out/view
quit
S
mkdir -p /tmp/out
for scene in "" interior:1e6 interior:1e7; do
  echo "=== view ${scene:-cbox} 1920x1080"
  LD_LIBRARY_PATH=$XLIB /usr/bin/time -v /tmp/furnace view $scene --width 1920 --height 1080 --script /tmp/s.txt --out /tmp/out/view 2>&1 \
    | grep -E 'state:|script:|saved|uploaded|viewing|error|Maximum resident|Elapsed' | grep -v 'script: (drag|wait-frames)'
done
for scene in interior:1e7; do
  echo "=== bench $scene 1920x1080, 1 and 16 spp per frame"
  /tmp/furnace bench --backend gpu --scene $scene --width 1920 --height 1080 --spp 1 --no-rays -q 2>&1 | tail -4
  /tmp/furnace bench --backend gpu --scene $scene --width 1920 --height 1080 --spp 16 --no-rays -q 2>&1 | tail -4
done
cat /tmp/xvfb.log | tail -3

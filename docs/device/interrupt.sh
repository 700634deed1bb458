# Ctrl-C inside long GPU passes, and what it costs a normal render, on the device:
# `.dev/furnace-new.xz` against `.dev/furnace-old.xz` (the version before), `.gl/` as README.md.
# 1. render speed (the summary line's Msamples/s; the progress line's first), new and old
#    interleaved, ROUNDS rounds;
# 2. the films of both at 1080p × 64 spp (RMSE 0 expected: pass cuts do not change a film);
# 3. one SIGINT AT seconds into a 4K render of 1024-bounce paths in a closed, nearly mirror cube
#    (make_mirror_cube.py): milliseconds to exit, what was saved; then two SIGINTs (exit 130 at
#    once, no crash).
set -u
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
for b in new old; do xz -dc .dev/furnace-$b.xz > /tmp/$b && chmod +x /tmp/$b; done
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
B=tests/data/references/lights/cbox_point.gltf; W=/tmp/w; M=$W/cube.gltf; mkdir -p $W
python3 docs/device/make_mirror_cube.py $M
for r in $(seq ${ROUNDS:-3}); do for b in new old; do
  /tmp/$b render --backend gpu --width 3840 --height 2160 --spp 256 --out $W/s$b 2>&1 | grep -o '[0-9.]* Msamples/s' | tail -1 | sed "s/^/speed 4K cbox $b: /"
  /tmp/$b render $B --backend gpu --width 1920 --height 1080 --spp 64 --bounces 8 --out $W/p$b 2>&1 | grep -o '[0-9.]* Msamples/s' | tail -1 | sed "s/^/speed 1080p cbox_point 8 bounces $b: /"
done; done
for b in new old; do /tmp/$b render --backend gpu --width 1920 --height 1080 --spp 64 --out $W/f$b --quiet; done
/tmp/new compare $W/fnew.exr $W/fold.exr | grep RMSE
# `exec`: the background job is furnace itself, so that the signal reaches it (a subshell running
# it would take the signal); a watchdog ends a run that outlives 120 s.
run() { exec /tmp/$1 render $M --backend gpu --width 3840 --height 2160 --spp 32 --bounces 1024 --russian-roulette off --out $W/i$1 > $W/i$1.log 2>&1; }
watch() { (sleep 120; kill -KILL $1 2>/dev/null) & }
for b in new old; do for at in ${AT:-2 10}; do
  rm -f $W/i$b.*; run $b & pid=$!; watch $pid
  sleep $at; sent=$(date +%s%N); kill -INT $pid; wait $pid; rc=$?; end=$(date +%s%N)
  echo "interrupt $b at ${at} s: exit $rc, $(( (end - sent) / 1000000 )) ms after SIGINT"
  grep -v '^wrote\|^to continue' $W/i$b.log | tail -2 | cut -c1-200
done; done
for k in 1 2 3; do
  run new & pid=$!; watch $pid; sleep 4; kill -INT $pid; sleep 0.3; kill -INT $pid; wait $pid
  echo "two SIGINTs, new: exit $?"
done

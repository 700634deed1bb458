#!/bin/bash
# Two small parts of the traversal timed by leaving them out, interleaved, two rounds, on five
# speed configurations: the per-invocation trace counters (FURNACE_NO_TRACE_COUNTERS=1) and
# the stack's overflow shift loop (FURNACE_SHADER_EDIT with edits/no-stack-shift.txt; the
# stack sized by the tree never overflows, so the images are the same). Needs .gl/,
# .dev/furnace-new.xz, .dev/sc/; no Mitsuba.
xz -dc .dev/furnace-new.xz > /tmp/fnew; chmod +x /tmp/fnew
source docs/device/speed-env.sh
E=$PWD/docs/device/edits
r="--sampler random --min-seconds 1"
for round in 1 2; do for i in 1 2 3 4 6; do sc=${scenes[$i]}; n=${sc%%|*}; a=${sc#*|}
  bench "$n default" fnew $a $r
  FURNACE_NO_TRACE_COUNTERS=1 bench "$n no-trace-counters" fnew $a $r
  FURNACE_SHADER_EDIT=$E/no-stack-shift.txt bench "$n no-stack-shift" fnew $a $r
done; done

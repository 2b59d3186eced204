#!/bin/bash
# Session 12, H200 (issue 15): accuracy against time of the light maps' guard
# (rt.light_map_guard 0 = every shadow ray traced .. 8), living room and gallery cameras 0-2, each
# value beside the stand-alone in its own process; then rt.max_depth 1..8 against depth 16
# (benchmarks.hybrid_rt --depth-sweep) on the living room. Writes under $OUT.
set -u
mkdir -p $OUT/guard
for s in rt_living_room rt_gallery; do
  for g in 0 1 2 4 8; do
    timeout 70 python3 -m benchmarks.hybrid_rt --scenes $s --cameras 0,1,2 --frames 10 --no-raster --param rt.light_map_guard=$g --json $OUT/guard/${s}_g$g.jsonl > /dev/null 2>&1; echo "$s guard $g rc=$?"
  done
done
timeout 120 python3 -m benchmarks.hybrid_rt --depth-sweep --scenes rt_living_room --cameras 1 --frames 10 > $OUT/guard/depth_sweep.md 2>/dev/null; echo "depth sweep rc=$?"
tar czf $OUT/guard.tgz -C $OUT guard && rm -rf $OUT/guard

#!/bin/bash
# Session 7, H200 call 1: ray tracing (issue 15) figures. Writes under $OUT.
set -u
for s in rt_living_room rt_conference rt_gallery; do
  timeout 100 python3 -m benchmarks.hybrid_rt --scenes $s --frames 20 --json $OUT/hybrid_$s.jsonl > $OUT/hybrid_$s.md 2>&1; echo "hybrid $s rc=$?"
done
for s in rt_living_room rt_gallery; do
  for g in rt_hybrid rt_standalone; do
    timeout 40 python3 -m rgraph run $g --scene graphs/scenes/$s.yaml --camera 0 --size 1280x720 --frames 20 --no-check-data --timings $OUT/timings_${g}_$s.txt --out $OUT/${g}_$s.png > $OUT/run_${g}_$s.txt 2>&1; echo "run $g $s rc=$?"
  done
done
timeout 150 python3 -m rgraph sweep rt_standalone --scene graphs/scenes/rt_living_room.yaml --size 1280x720 --frames 20 --workers 1 --knob rt.max_depth=1,2,3,4,5,6,7,8 --reference rt.max_depth=16 -o $OUT/depth > $OUT/depth_sweep.txt 2>&1; echo "depth sweep rc=$?"

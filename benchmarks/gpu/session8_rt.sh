#!/bin/bash
# Session 8, H200: ray tracing (issue 15) after the wavefront ray tree and the one-pass 64-bit
# visibility buffer. Writes under $OUT. Run from the checkout: source .gl/enter.sh first.
# Then one A/B: list appends with one atomic per subgroup (rt.wave_subgroup=1), living room only.
set -u
for s in rt_living_room rt_conference rt_gallery; do
  timeout 150 python3 -m benchmarks.hybrid_rt --scenes $s --frames 20 --json $OUT/hybrid_$s.jsonl > $OUT/hybrid_$s.md 2>&1; echo "hybrid $s rc=$?"
done
timeout 80 python3 -m benchmarks.hybrid_rt --scenes rt_living_room --cameras 0,1,4 --frames 20 --no-raster --param rt.wave_subgroup=1 --json $OUT/hybrid_subgroup_rt_living_room.jsonl > $OUT/hybrid_subgroup_rt_living_room.md 2>&1; echo "subgroup rc=$?"

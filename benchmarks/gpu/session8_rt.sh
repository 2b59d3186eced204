#!/bin/bash
# Issue 15, H200: the wavefront hybrid (graphs/rt_hybrid.yaml) against stand-alone, with the
# async-shading variant (benchmarks/graphs/rt_hybrid_async.yaml: async_ columns), one process per
# scene; then the rt.wave_subgroup=1 A/B on living room cameras 0, 1, 4. Writes under $OUT;
# fits one 10-minute device call (3 x 150 s + 80 s). Run from the checkout after source .gl/enter.sh.
set -u
for s in rt_living_room rt_conference rt_gallery; do
  timeout 150 python3 -m benchmarks.hybrid_rt --scenes $s --frames 20 --no-raster --async --json $OUT/hybrid_$s.jsonl > $OUT/hybrid_$s.md 2>&1; echo "hybrid $s rc=$?"
done
timeout 80 python3 -m benchmarks.hybrid_rt --scenes rt_living_room --cameras 0,1,4 --frames 20 --no-raster --param rt.wave_subgroup=1 --json $OUT/hybrid_subgroup_rt_living_room.jsonl > $OUT/hybrid_subgroup_rt_living_room.md 2>&1; echo "subgroup rc=$?"

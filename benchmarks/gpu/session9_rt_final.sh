#!/bin/bash
# Session 9, H200 (issue 15): Table 3 with the session-9 hybrid defaults (trees walked in-thread by
# the shade pass; crack-free compute visibility buffer), one process per scene; then the
# level-by-level variant (rt.wavefront=1) on the gallery for the side-by-side. Writes under $OUT.
set -u
for s in rt_living_room rt_conference rt_gallery; do
  timeout 100 python3 -m benchmarks.hybrid_rt --scenes $s --frames 10 --no-raster --json $OUT/final_$s.jsonl > $OUT/final_$s.md 2>&1; echo "hybrid $s rc=$?"
done
timeout 90 python3 -m benchmarks.hybrid_rt --scenes rt_gallery --frames 10 --no-raster --param rt.wavefront=1 --json $OUT/wave_rt_gallery.jsonl > $OUT/wave_rt_gallery.md 2>&1; echo "wave gallery rc=$?"

#!/bin/bash
# Session 17, H200 (issue 15): Table 3 with the compute shading pass (graphs/rt_hybrid.yaml:
# rt_hybrid_first shades every pixel that needs no ray, the shade pass traces only the listed
# ones; light-map footprints along the whole ray path) beside the hybrid as it was
# (--all-pixels: benchmarks/graphs/rt_hybrid_all_pixels.yaml), one process per scene, the plans
# alternating in chunks. SCENES overrides the scene list. Run from a checkout: source
# .gl/enter.sh first. Writes under $OUT.
set -u
mkdir -p $OUT/rt
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,temperature.gpu --format=csv > $OUT/rt/gpu_start.txt 2>&1
for s in ${SCENES-rt_living_room rt_conference rt_gallery}; do
  timeout ${SCENE_TIMEOUT-180} python3 -m benchmarks.hybrid_rt --scenes $s --frames ${FRAMES-10} --no-raster --all-pixels \
    --json $OUT/rt/table_$s.jsonl > $OUT/rt/table_$s.md 2>$OUT/rt/table_$s.err; echo "table $s rc=$?"
done
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,temperature.gpu --format=csv > $OUT/rt/gpu_end.txt 2>&1

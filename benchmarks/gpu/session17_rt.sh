#!/bin/bash
# Session 17, H100/H200 (issue 15): Table 3 of graphs/rt_hybrid.yaml beside the hybrid with the
# compute shading pass (--first: benchmarks/graphs/rt_hybrid_first.yaml, rt_hybrid_first shades
# every pixel that needs no ray, the shade pass traces only the listed ones), one process per
# scene, the plans alternating in chunks. (The call recorded in docs/runs/h100-session17 ran at
# dfa9a7f, where the compute pass was in graphs/rt_hybrid.yaml and the every-pixel graph was the
# variant, with --all-pixels: the same two graphs, the columns the other way round.)
# SCENES overrides the scene list. Run from a checkout: source .gl/enter.sh first. Writes under $OUT.
set -u
mkdir -p $OUT/rt
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,temperature.gpu --format=csv > $OUT/rt/gpu_start.txt 2>&1
for s in ${SCENES-rt_living_room rt_conference rt_gallery}; do
  timeout ${SCENE_TIMEOUT-180} python3 -m benchmarks.hybrid_rt --scenes $s --frames ${FRAMES-10} --no-raster --first \
    --json $OUT/rt/table_$s.jsonl > $OUT/rt/table_$s.md 2>$OUT/rt/table_$s.err; echo "table $s rc=$?"
done
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,temperature.gpu --format=csv > $OUT/rt/gpu_end.txt 2>&1

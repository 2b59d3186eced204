#!/bin/bash
# Session 10, H200: where the time of the ray-traced frames goes (issue 15) and whether draw
# order matters to instanced stereo (issue 18).
# 1. Shadow rays: gallery and living room as bundled, with only their directional light
#    (benchmarks/graphs/rt_*_sun.yaml) and with no lights (rt_*_dark.yaml: camera rays and
#    the reflection/refraction trees only), cameras 0-2, stand-alone and hybrid side by side.
# 2. Draw order: vr_instanced and its point mirror (benchmarks/graphs/vr_instanced_mirrored.yaml:
#    the same image mirrored, the draw order reversed relative to the view), mono and stereo.
# Run from a checkout: source .gl/enter.sh first. ORDER_SCENES= (empty) skips part 2.
set -u
mkdir -p $OUT/rt $OUT/order
for s in gallery living_room; do
  for v in "rt_$s" "benchmarks/graphs/rt_${s}_sun.yaml" "benchmarks/graphs/rt_${s}_dark.yaml"; do
    name=$(basename "$v" .yaml)
    timeout 120 python3 -m benchmarks.hybrid_rt --scenes "$v" --cameras 0,1,2 --frames 10 --no-raster --json $OUT/rt/$name.jsonl > $OUT/rt/$name.md 2>&1; echo "$name rc=$?"
  done
done
for scene in ${ORDER_SCENES-graphs/scenes/vr_instanced.yaml benchmarks/graphs/vr_instanced_mirrored.yaml}; do
  for views in 1 2; do
    name=$(basename $scene .yaml)_v$views
    timeout 60 python3 -m rgraph run clustered --scene $scene -p views=$views --size 1920x1080 --frames 60 --warmup 0.5 --no-check-data --allow-include-outside > $OUT/order/$name.txt 2>&1; echo "$name rc=$?"
  done
done
# few files come back from the device: one archive
tar czf $OUT/cost_probe.tgz -C $OUT rt order && rm -rf $OUT/rt $OUT/order

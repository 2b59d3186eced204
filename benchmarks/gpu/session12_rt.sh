#!/bin/bash
# Session 12, H200 (issue 15): Table 3 with the light maps (graphs/rt_hybrid.yaml defaults:
# shadow rays traced only where the light maps cannot tell) beside the same hybrid tracing every
# shadow ray (--traced: rt.light_maps=0), one process per scene; then the maps' one-time build
# (the light_maps pass of a single frame, no warm-up). SCENES overrides the scene list.
# Run from a checkout: source .gl/enter.sh first. Writes under $OUT.
set -u
mkdir -p $OUT/rt
for s in ${SCENES-rt_living_room rt_conference rt_gallery}; do
  timeout 200 python3 -m benchmarks.hybrid_rt --scenes $s --frames 10 --no-raster --traced --json $OUT/rt/table_$s.jsonl > $OUT/rt/table_$s.md 2>$OUT/rt/table_$s.err; echo "table $s rc=$?"
  timeout 60 python3 -m rgraph run rt_hybrid --scene graphs/scenes/$s.yaml --size 1280x720 --frames 1 --warmup 0 --timings $OUT/rt/build_$s.json --no-check-data > $OUT/rt/build_$s.txt 2>&1; echo "build $s rc=$?"
done
tar czf $OUT/rt.tgz -C $OUT rt && rm -rf $OUT/rt

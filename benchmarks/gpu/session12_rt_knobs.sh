#!/bin/bash
# Session 12, H200 (issue 15): the light maps' knobs on the scenes with point lights: finer maps
# (rt.light_map_scale=3) and a looser guard (rt.light_map_guard=4) against the defaults of
# session12_rt.sh, each beside the stand-alone in its own process. Writes under $OUT.
set -u
mkdir -p $OUT/knobs
for s in ${SCENES-rt_living_room rt_conference}; do
  for knob in rt.light_map_scale=3 rt.light_map_guard=4; do
    timeout 140 python3 -m benchmarks.hybrid_rt --scenes $s --frames 10 --no-raster --param $knob --json $OUT/knobs/${s}_$knob.jsonl > $OUT/knobs/${s}_$knob.md 2>/dev/null; echo "$s $knob rc=$?"
  done
done
tar czf $OUT/knobs.tgz -C $OUT knobs && rm -rf $OUT/knobs

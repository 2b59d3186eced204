#!/bin/bash
# Session 7, H200: issue 21's sweeps in worker processes. Text only under $OUT (<= 8 files).
set -u
W=/tmp/sw; rm -rf $W; mkdir -p $W
timeout 330 python3 benchmarks/sweep_throughput.py --size 1920x1080 --frames 10 --workers 4 -o $W/tp --json $OUT/sweep_throughput.json > $OUT/sweep_throughput.txt 2>&1; echo "throughput rc=$?"
timeout 100 python3 -m rgraph sweep rt_standalone --scene graphs/scenes/rt_living_room.yaml --size 1280x720 --frames 20 --workers 4 --no-progress --knob rt.max_depth=1,2,3,4,5,6,7,8 --reference rt.max_depth=16 -o $W/depth > $W/depth.log 2>&1; echo "depth rc=$?"
timeout 100 python3 -m rgraph sweep clustered --scene graphs/scenes/many_lights.yaml --size 1920x1080 --frames 20 --workers 4 --no-progress --knob clusters.tile=16,32,64,128 --knob clusters.slices=8,16,24,48 --reference clusters.tile=16 --reference clusters.slices=48 -o $W/clusters > $W/clusters.log 2>&1; echo "clusters rc=$?"
cd $W && tar czf $OUT/sweeps_text.tgz $(find . -name '*.md' -o -name '*.csv' -o -name '*.log' -o -name '*.json') && ls -la $OUT

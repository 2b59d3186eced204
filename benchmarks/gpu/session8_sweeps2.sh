#!/bin/bash
# Session 8, H200 call 3 (issue 21), after the warm-up fix (images no longer depend on the
# warm-up's frame count): 1. one pool vs one process per group on the two groups whose outputs
# differed in call 2 (hbao, sss); 2. every committed sweep in ONE command, one pool.
set -u
W=/tmp/sw8b; rm -rf $W; mkdir -p $W
timeout 110 python3 benchmarks/sweep_throughput.py --size 1280x720 --frames 10 --groups hbao,sss \
  --pools 4x8 -o $W/tp --json $OUT/sweep_identity.json > $OUT/sweep_identity.txt 2>&1
echo "identity rc=$?"
timeout 330 python3 benchmarks/sweeps.py --size 1920x1080 --frames 10 --workers 8 --per-worker 8 --no-progress \
  -o $W/acc > $OUT/sweeps.log 2>&1
echo "sweeps rc=$?"
python3 benchmarks/sweep_bundle.py pack $W/acc $OUT; echo "bundle rc=$?"

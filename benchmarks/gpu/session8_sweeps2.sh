#!/bin/bash
# Session 8, H200, second sweeps call (after call 2 showed the parent process bound the pool and
# the wall-time warm-up made surgery's images run-dependent): the throughput again, then every
# committed sweep in ONE command at 1920x1080 (call 2's stopped at its 200 s limit before
# `clusters`). Expected 6-7 minutes, at most 9 (220 + 330 s of timeouts). 6 files under $OUT.
set -u
W=/tmp/sw8b; rm -rf $W; mkdir -p $W
timeout 220 python3 benchmarks/sweep_throughput.py --size 1280x720 --frames 10 --groups hbao,sss,rt,clusters \
  --pools 4x8,8x8 -o $W/tp --json $OUT/sweep_throughput.json > $OUT/sweep_throughput.txt 2>&1
echo "throughput rc=$?"
timeout 330 python3 benchmarks/sweeps.py --size 1920x1080 --frames 10 --workers 8 --per-worker 8 --no-progress \
  -o $W/acc > $OUT/sweeps.log 2>&1
echo "sweeps rc=$?"
cp $W/acc/accuracy-vs-time.md $OUT/ 2>/dev/null
python3 benchmarks/sweep_bundle.py pack $W/acc $OUT; echo "bundle rc=$?"
ls -la $OUT

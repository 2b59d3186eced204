#!/bin/bash
# Session 8, H200: issue 21 part 3. The committed sweeps (docs/accuracy-vs-time.md's five
# groups + rt.max_depth + clusters.tile/slices) in ONE command through one worker pool, and
# the throughput of that pool vs one process per group. Expected 5-6 minutes (at most 8.5: 300 + 200 s of timeouts); every step has
# its own timeout and writes what it measured so far. 6 files under $OUT (text, CSV, PNG).
set -u
W=/tmp/sw8; rm -rf $W; mkdir -p $W
# 1. throughput: one process per group vs one pool (4x8, 8x8: N workers x K settings each;
#    8x1: one process per setting, as in session 7), 1280x720, 10 frames, 4 groups (29 renderings)
timeout 300 python3 benchmarks/sweep_throughput.py --size 1280x720 --frames 10 --groups hbao,sss,rt,clusters \
  --pools 4x8,8x8,8x1 -o $W/tp --json $OUT/sweep_throughput.json > $OUT/sweep_throughput.txt 2>&1
echo "throughput rc=$?"
# 2. the committed sweeps, every group, one command, one pool of 8 workers x 8 settings, 1920x1080
timeout 200 python3 benchmarks/sweeps.py --size 1920x1080 --frames 10 --workers 8 --per-worker 8 --no-progress \
  -o $W/acc > $OUT/sweeps.log 2>&1
echo "sweeps rc=$?"
cp $W/acc/accuracy-vs-time.md $OUT/ 2>/dev/null
python3 benchmarks/sweep_bundle.py pack $W/acc $OUT; echo "bundle rc=$?"
ls -la $OUT

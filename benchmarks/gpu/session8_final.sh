#!/bin/bash
# Session 8, H200 last call (540 s of device time left): every committed sweep in ONE command
# through one pool (issue 21), then the hybrid ray tracing table of the wavefront branch,
# unpacked in _rt/ (issue 15). At most 5 files under $OUT.
set -u
W=/tmp/sw8c; rm -rf $W; mkdir -p $W
timeout 270 python3 benchmarks/sweeps.py --size 1920x1080 --frames 10 --workers 8 --per-worker 8 --no-progress \
  -o $W/acc > $OUT/sweeps.log 2>&1
echo "sweeps rc=$?"
python3 benchmarks/sweep_bundle.py pack $W/acc $OUT; echo "bundle rc=$?"
if [ -d _rt ]; then
  cd _rt && export PYTHONPATH=/tmp/site:$PWD
  for s in rt_living_room rt_conference rt_gallery; do
    timeout 75 python3 -m benchmarks.hybrid_rt --scenes $s --frames 10 --no-raster --json $W/h_$s.jsonl > $W/h_$s.md 2>&1
    echo "hybrid $s rc=$?"; cat $W/h_$s.md >> $OUT/hybrid.md; cat $W/h_$s.jsonl >> $OUT/hybrid.jsonl 2>/dev/null
  done
fi

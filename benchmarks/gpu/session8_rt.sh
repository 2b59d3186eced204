#!/bin/bash
# Session 8, H200: ray tracing (issue 15) after the wavefront ray tree and the one-pass 64-bit
# visibility buffer. Writes under $OUT. Run from the checkout: source .gl/enter.sh first.
set -u
for s in rt_living_room rt_conference rt_gallery; do
  timeout 170 python3 -m benchmarks.hybrid_rt --scenes $s --frames 20 --json $OUT/hybrid_$s.jsonl > $OUT/hybrid_$s.md 2>&1; echo "hybrid $s rc=$?"
done

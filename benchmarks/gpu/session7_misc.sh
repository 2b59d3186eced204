#!/bin/bash
# Session 7, H200: barrier cost (issue 19) and two logical devices on one GPU (issue 16); text only under $OUT.
set -u
timeout 150 python3 -m benchmarks.barrier_cost --size 1920x1080 --frames 300 --rounds 3 > $OUT/barrier_cost.txt 2>&1; echo "barrier rc=$?"
timeout 150 python3 -m benchmarks.multi_gpu --devices 0,0 --size 1920x1080 --frames 10 --out-json $OUT/multi_h200.json > $OUT/multi_gpu.txt 2>&1; echo "multi rc=$?"

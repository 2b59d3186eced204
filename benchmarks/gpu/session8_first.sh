#!/bin/bash
# Session 8, H200 call 1: multi-GPU study workloads on two logical devices (issue 16),
# the --naive-cpu device loss (issue 18), surgery's per-frame Python with the logic thread.
set -u
timeout 150 python3 -m benchmarks.multi_gpu --devices 0,0 --size 1920x1080 --frames 10 --rounds 2 --warmup-s 0.5 --graphs pixels --out-json $OUT/multi_pixels.json > $OUT/multi_pixels.txt 2>&1; echo "pixels rc=$?"
timeout 270 python3 -m benchmarks.multi_gpu --devices 0,0 --size 1920x1080 --frames 10 --rounds 2 --warmup-s 0.5 --graphs mesh --out-json $OUT/multi_mesh.json > $OUT/multi_mesh.txt 2>&1; echo "mesh rc=$?"
{
  for t in lighting_test vr_unique vr_instanced; do
    echo "== $t naive 1920x1080 (no validation)"
    timeout 25 python3 -m rgraph run clustered --scene graphs/scenes/$t.yaml --naive-cpu --size 1920x1080 --frames 30 --no-check-data; echo "rc=$?"
  done
  echo "== vr_instanced naive 320x180 --validate"
  timeout 40 python3 -m rgraph run clustered --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 320x180 --frames 4 --validate --no-check-data; echo "rc=$?"
} > $OUT/naive.txt 2>&1; echo "naive done"
timeout 60 python3 benchmarks/frame_cpu.py --passes real --size 1920x1080 --frames 1500 --rounds 1 --logic-hz 60 > $OUT/frame_cpu_logic60.txt 2>&1; echo "frame_cpu rc=$?"

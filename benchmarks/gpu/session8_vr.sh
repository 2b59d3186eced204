#!/bin/bash
# Session 8, H200 (issue 18): render-thread CPU of the four VR tests (gpu and naive draw modes in
# separate processes, so a lost device costs one mode only), surgery's Python per frame with and
# without the logic thread, naive instanced on its own. Run from a checkout: source .gl/enter.sh first.
set -u
timeout 110 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes gpu --json $OUT/vr_gpu.json > $OUT/vr_gpu.txt 2>&1; echo "vr gpu rc=$?"
timeout 90 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes naive --json $OUT/vr_naive.json > $OUT/vr_naive.txt 2>&1; echo "vr naive rc=$?"
python3 -m benchmarks.vr_tests --from-json $OUT/vr_gpu.json $OUT/vr_naive.json > $OUT/vr_table.md 2>&1; echo "table rc=$?"
timeout 100 python3 benchmarks/frame_cpu.py --passes real --size 1920x1080 --frames 2000 --rounds 1 > $OUT/frame_cpu_real.txt 2>&1; echo "frame_cpu rc=$?"
timeout 100 python3 benchmarks/frame_cpu.py --passes real --size 1920x1080 --frames 2000 --rounds 1 --logic-hz 60 > $OUT/frame_cpu_logic60.txt 2>&1; echo "frame_cpu logic rc=$?"
timeout 40 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --tests instanced,lighting --views 1 --modes gpu --timestamps-every 1 --json $OUT/vr_ts1.json > $OUT/vr_ts1.txt 2>&1; echo "vr timestamps every frame rc=$?"
timeout 60 python3 -m benchmarks.vr_tests --size 1280x720 --frames 60 --warmup 0.3 --tests instanced,unique --modes gpu --json $OUT/vr_720p.json > $OUT/vr_720p.txt 2>&1; echo "vr 720p rc=$?"
{
  echo "== vr_instanced naive 1920x1080 (no validation)"
  timeout 40 python3 -m rgraph run clustered --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 1920x1080 --frames 60 --no-check-data; echo "rc=$?"
  echo "== vr_instanced draw.mode=cpu 1920x1080 (host-written Draws, one instanced draw; tells a naive loss apart)"
  timeout 40 python3 -m rgraph run clustered --scene graphs/scenes/vr_instanced.yaml -p draw.mode=cpu --size 1920x1080 --frames 60 --no-check-data; echo "rc=$?"
} > $OUT/naive_instanced.txt 2>&1; echo "naive instanced done"

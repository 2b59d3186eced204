#!/bin/bash
# Session 7, H200 last call: VR tests (issue 18), two logical devices (16), render-thread CPU of
# surgery (18), sweeps in 8 worker processes (21). Text only under $OUT (<= 8 files).
set -u
timeout 130 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 100 --warmup 0.3 --logic-hz 60 --json $OUT/vr_tests_h200.json > $OUT/vr_tests_h200.txt 2>&1; echo "vr rc=$?"
timeout 90 python3 -m benchmarks.multi_gpu --devices 0,0 --size 1920x1080 --frames 10 --rounds 2 --warmup-s 0.3 --graphs surgery,pixels,mesh --transfers shared --pipelined off,on --balances static --out-json $OUT/multi_h200.json > $OUT/multi_h200.txt 2>&1; echo "multi rc=$?"
timeout 35 python3 benchmarks/frame_cpu.py --passes real --size 1920x1080 --frames 500 --rounds 1 > $OUT/frame_cpu_real_1080p.txt 2>&1; echo "frame_cpu rc=$?"
S=$(date +%s%N); timeout 70 python3 benchmarks/sweeps.py --no-progress --size 1920x1080 --frames 10 --groups hbao,sss,bloom --workers 8 -o /tmp/w8 > $OUT/sweeps_w8.txt 2>&1; rc=$?; echo "sweeps rc=$rc wall $(( ($(date +%s%N) - S) / 1000000 )) ms" | tee -a $OUT/sweeps_w8.txt
cp /tmp/w8/accuracy-vs-time.md $OUT/accuracy_w8.md 2>/dev/null

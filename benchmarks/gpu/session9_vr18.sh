#!/bin/bash
# Session 9, H200 (issue 18): the session-9 changes. Naive instanced with direct draws (the new
# default) and the old indirect path under the validated submission structure without the layer;
# surgery without the logic thread; the four VR tests, gpu and naive, every pass on one VkQueue
# (each row its own process). Fits the session's last ~260 s of device time.
# Run from a checkout: source .gl/enter.sh first.
set -u
one() { local name=$1; shift; echo "== $name: $*"; timeout 30 "$@" 2>&1 | grep -v -E '^(│|┃|┏|┡|└|┗)' | tail -4; echo "rc=${PIPESTATUS[0]}"; }
{
  one direct-1080p-30 python3 -m rgraph run clustered --no-check-data --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 1920x1080 --frames 30 --warmup 0
  one indirect-submit-per-pass-3 env RGRAPH_SUBMIT_PER_PASS=1 python3 -m rgraph run clustered --no-check-data --scene graphs/scenes/vr_instanced.yaml --naive-cpu -p draw.naive=indirect --size 1920x1080 --frames 3 --warmup 0
} > $OUT/naive9.txt 2>&1; echo "naive done"
timeout 40 python3 benchmarks/frame_cpu.py --passes real --size 1920x1080 --frames 1000 --rounds 1 > $OUT/frame_cpu_real.txt 2>&1; echo "frame_cpu rc=$?"
timeout 150 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes gpu,naive --queues one --json $OUT/vr_one.json > $OUT/vr_one.txt 2>&1; echo "vr one queue rc=$?"

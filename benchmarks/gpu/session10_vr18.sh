#!/bin/bash
# Session 10, H200 (issue 18): the session-9 changes. Naive instanced with direct draws (the new
# default) and the old indirect path under the validated submission structure without the layer;
# the four VR tests, gpu and naive, every pass on one VkQueue (each row its own process); the
# same gpu rows mono on the device's queues for comparison; skinned with its logic tick on 4 threads; surgery without the logic thread.
# Run from a checkout: source .gl/enter.sh first. About 4 minutes.
set -u
one() { local name=$1; shift; echo "== $name: $*"; timeout 40 "$@" 2>&1 | grep -v -E '^(│|┃|┏|┡|└|┗)' | tail -4; echo "rc=${PIPESTATUS[0]}"; }
{
  one direct-1080p-30 python3 -m rgraph run clustered --no-check-data --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 1920x1080 --frames 30 --warmup 0
  one indirect-submit-per-pass-3 env RGRAPH_SUBMIT_PER_PASS=1 python3 -m rgraph run clustered --no-check-data --scene graphs/scenes/vr_instanced.yaml --naive-cpu -p draw.naive=indirect --size 1920x1080 --frames 3 --warmup 0
} > $OUT/naive10.txt 2>&1; echo "naive done"
timeout 200 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes gpu,naive --queues one --json $OUT/vr_one.json > $OUT/vr_one.txt 2>&1; echo "vr one queue rc=$?"
timeout 60 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes gpu --views 1 --queues device --json $OUT/vr_device.json > $OUT/vr_device.txt 2>&1; echo "vr device queues rc=$?"
timeout 40 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --tests skinned --modes gpu --queues one -p skin.threads=4 --json $OUT/vr_skin4.json > $OUT/vr_skin4.txt 2>&1; echo "vr skinned 4 logic threads rc=$?"
timeout 60 python3 benchmarks/frame_cpu.py --passes real --size 1920x1080 --frames 1000 --rounds 1 > $OUT/frame_cpu_real.txt 2>&1; echo "frame_cpu rc=$?"

#!/bin/bash
# Session 10, H200, the last call: the merged main. (1) The four VR tests, mono and stereo,
# GPU-driven (draw.order front_to_back, skinning states in a worker process), logic thread at
# 60 Hz, one VkQueue, each row its own process; (2) skinned with the old composition
# (skin.worker=thread) beside it; (3) skin_anim on this host; (4) compile of the 1,000-pass
# graph on this host's CPU. Run from a checkout: source .gl/enter.sh first.
set -u
timeout 200 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes gpu --queues one \
  --json $OUT/vr_final.json > $OUT/vr_final.txt 2>&1; echo "vr rc=$?"
timeout 90 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes gpu --queues one \
  --tests skinned --views 1,2 -p skin.worker=thread --json $OUT/vr_skin_thread.json > $OUT/vr_skin_thread.txt 2>&1; echo "vr thread rc=$?"
timeout 120 python3 -m benchmarks.skin_anim --ticks 120 --threads 1,4 --worker --contention --frames 600 > $OUT/skin_anim.txt 2>&1; echo "skin_anim rc=$?"
timeout 150 python3 benchmarks/compile_scaling.py --sizes 250,1000,4000 --chain 10000 --side-effects 5000 --phases > $OUT/compile_scaling.txt 2>&1; echo "compile rc=$?"

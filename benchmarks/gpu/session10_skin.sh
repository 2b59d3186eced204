#!/bin/bash
# Session 10, H200 (issue 18, skinned): the logic tick and the render thread with the skinning
# states evaluated in a worker process (skin.worker=process, the default) against the logic
# thread itself (skin.worker=thread, the old composition), skinned rows only, one VkQueue.
# ~150 s of device time. Run from a checkout: source .gl/enter.sh first.
set -u
timeout 240 python3 -m benchmarks.skin_anim --ticks 120 --threads 1,2,4,8 --worker --contention --frames 600 \
  > $OUT/skin_anim.txt 2>&1; echo "skin_anim rc=$?"
for cfg in "process 1" "process 4" "thread 1"; do
  set -- $cfg
  timeout 120 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --modes gpu \
    --queues one --tests skinned --views 1,2 -p skin.worker=$1 -p skin.threads=$2 \
    --json $OUT/skinned_$1_$2.json > $OUT/skinned_$1_$2.txt 2>&1; echo "vr skinned $1 $2 rc=$?"
done
timeout 60 python3 -m rgraph run clustered --no-check-data --scene graphs/scenes/vr_skinned.yaml --size 1920x1080 \
  --frames 300 --warmup 1 --logic-hz 60 > $OUT/run_skinned.txt 2>&1; echo "rgraph run rc=$?"

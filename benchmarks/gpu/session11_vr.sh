#!/bin/bash
# Session 11, H200 (issue 18: render-thread CPU <= 100 us per frame): the render thread's new
# path against the old one, skinned and lighting, mono and stereo, one VkQueue, logic at 60 Hz,
# each row its own process. Switches (environment, inherited by the rows):
#   new  : defaults: one command buffer / one VkSubmitInfo2 per frame (batch cuts only where a
#          semaphore is needed), the per-run update closure (SceneFrames.frame_update);
#   old  : RGRAPH_BATCH_CUTS=plan RGRAPH_FRAME_UPDATE=method, the render path of main 0a194d8
#          (two command buffers / VkSubmitInfo2 per frame, SceneFrames.update per frame);
#   cuts : the new update with the old cuts (new against cuts: what the one command buffer gives);
#   poll : new, and RGRAPH_FENCE_WAIT=poll (diagnostic: the thread polls its fences instead of
#          sleeping: is the time after a long wait the cold wake-up's? burns the wait's CPU);
#   lighting at 3840x2160 mono, new and old: lighting with a frame as long as skinned's
#          (~9 ms): does the render thread's time grow with the wait alone?
# new and old run twice, interleaved (the host drifts between calls). ~5 min of device time.
# Run from a checkout: source .gl/enter.sh first. Results: $OUT/session11_vr.tgz.
# SIZE, SIZE4K, FRAMES, PY override the defaults (a lavapipe smoke: SIZE=64x36 SIZE4K=96x54 FRAMES=4).
set -u
SIZE=${SIZE:-1920x1080}; SIZE4K=${SIZE4K:-3840x2160}; FRAMES=${FRAMES:-120}; PY=${PY:-python3}
mkdir -p $OUT/vr11
VR="$PY -m benchmarks.vr_tests --frames $FRAMES --warmup 0.3 --logic-hz 60 --modes gpu --queues one"
run() {  # name, size, tests, views, env...
  local name=$1 size=$2 tests=$3 views=$4; shift 4
  env "$@" timeout 150 $VR --size $size --tests $tests --views $views --json $OUT/vr11/$name.json \
    > $OUT/vr11/$name.txt 2>&1; echo "$name rc=$?"
}
OLD="RGRAPH_BATCH_CUTS=plan RGRAPH_FRAME_UPDATE=method"
uptime > $OUT/vr11/load_start.txt
run new_1 $SIZE skinned,lighting 1,2 RGRAPH_BATCH_CUTS=queue
run old_1 $SIZE skinned,lighting 1,2 $OLD
run new_2 $SIZE skinned,lighting 1,2 RGRAPH_BATCH_CUTS=queue
run old_2 $SIZE skinned,lighting 1,2 $OLD
run cuts $SIZE skinned,lighting 1,2 RGRAPH_BATCH_CUTS=plan
run poll $SIZE skinned,lighting 1,2 RGRAPH_FENCE_WAIT=poll
run lighting4k_new $SIZE4K lighting 1 RGRAPH_BATCH_CUTS=queue
run lighting4k_old $SIZE4K lighting 1 $OLD
uptime > $OUT/vr11/load_end.txt
tar czf $OUT/session11_vr.tgz -C $OUT vr11 && rm -rf $OUT/vr11 && echo "tar rc=$?"

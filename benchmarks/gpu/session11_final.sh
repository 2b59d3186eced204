#!/bin/bash
# Session 11's last H200 call (issue 18 render-thread CPU, issue 15 deformable RT, issue 19 compile
# on the H200 host): main with the one-command-buffer frame, the per-run update closure and the
# logic rate as the schedule kept; the deformed RT tables. Run from a checkout after
# `source .gl/enter.sh`. Results: $OUT/session11_final.tgz.
set -u
PY=${PY:-python3}; SIZE=${SIZE:-1920x1080}; FRAMES=${FRAMES:-120}
mkdir -p $OUT/final11
uptime > $OUT/final11/load_start.txt
VR="$PY -m benchmarks.vr_tests --size $SIZE --frames $FRAMES --warmup 0.3 --logic-hz 60 --modes gpu --queues one"
for round in 1 2; do
  timeout 240 $VR --json $OUT/final11/vr_round$round.json > $OUT/final11/vr_round$round.txt 2>&1
  echo "vr round $round rc=$?"
done
timeout 120 $PY benchmarks/rt_deform_cost.py --scene graphs/scenes/cct.yaml --static --frames 120 --size 1280 720 \
  > $OUT/final11/rt_deform_cost.txt 2>&1; echo "rt_deform_cost rc=$?"
timeout 120 $PY benchmarks/compile_scaling.py --sizes 1000 --chain 0 --side-effects 0 --phases --repeats 30 \
  > $OUT/final11/compile_1000.txt 2>&1; echo "compile rc=$?"
uptime > $OUT/final11/load_end.txt
tar czf $OUT/session11_final.tgz -C $OUT final11 && rm -rf $OUT/final11 && echo "tar rc=$?"

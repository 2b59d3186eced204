#!/bin/bash
# Session 11, a second short H200 call: the host cost of deformable meshes in a ray tracing plan
# (benchmarks/rt_deform_cost.py, compiled for the device), and a third round of the VR tests.
# Run from a checkout after `source .gl/enter.sh`. Results: $OUT/session11_extra.tgz.
set -u
PY=${PY:-python3}
mkdir -p $OUT/extra11
uptime > $OUT/extra11/load_start.txt
for g in rt_standalone rt_hybrid; do
  timeout 150 $PY benchmarks/rt_deform_cost.py --graph $g --scene graphs/scenes/cct.yaml --static --frames 120 \
    --size 1280 720 > $OUT/extra11/rt_deform_cost_$g.txt 2>&1; echo "rt_deform_cost $g rc=$?"
done
timeout 240 $PY -m benchmarks.vr_tests --size 1920x1080 --frames 120 --warmup 0.3 --logic-hz 60 --modes gpu \
  --queues one --json $OUT/extra11/vr_round3.json > $OUT/extra11/vr_round3.txt 2>&1; echo "vr round 3 rc=$?"
uptime > $OUT/extra11/load_end.txt
tar czf $OUT/session11_extra.tgz -C $OUT extra11 && rm -rf $OUT/extra11 && echo "tar rc=$?"

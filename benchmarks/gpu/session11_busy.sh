#!/bin/bash
# Session 11: how often the unique test's mono row leaves the GPU idle (round 1 of
# session11_final.sh: 92.4% busy; rounds 2-3: 99.1%). Six unique mono rows and two lighting
# mono rows, each its own process, the same flags as the VR tables. Results: $OUT/session11_busy.tgz.
set -u
PY=${PY:-python3}
mkdir -p $OUT/busy11
VR="$PY -m benchmarks.vr_tests --size 1920x1080 --frames 120 --warmup 0.3 --logic-hz 60 --modes gpu --queues one --views 1"
for k in 1 2 3 4 5 6; do
  timeout 90 $VR --tests unique --json $OUT/busy11/unique_$k.json > $OUT/busy11/unique_$k.txt 2>&1; echo "unique $k rc=$?"
done
for k in 1 2; do
  timeout 90 $VR --tests lighting --json $OUT/busy11/lighting_$k.json > $OUT/busy11/lighting_$k.txt 2>&1; echo "lighting $k rc=$?"
done
tar czf $OUT/session11_busy.tgz -C $OUT busy11 && rm -rf $OUT/busy11 && echo "tar rc=$?"

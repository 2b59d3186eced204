#!/bin/bash
# Session 10, H200 (issue 18): why instanced stereo costs 3x mono (depth prepass 3.0x, forward
# 3.4x) while the other tests cost 1.8-2.0x. Variants, each its own process: mono at 1920x1080
# and at 3840x1080 (twice the pixels, one layer), stereo with the default 64 mm and with 0 mm
# between the eyes (both eyes the same view), and lighting mono/stereo as a control.
# Run from a checkout: source .gl/enter.sh first.
set -u
row() { local name=$1; shift; echo "== $name: $*"; timeout 60 python3 -m benchmarks.vr_tests --frames 40 --warmup 0.3 --modes gpu --queues one "$@" --json $OUT/$name.json > $OUT/$name.txt 2>&1; echo "rc=$?"; }
row inst_mono_1080 --size 1920x1080 --tests instanced --views 1
row inst_mono_2160w --size 3840x1080 --tests instanced --views 1
row inst_stereo --size 1920x1080 --tests instanced --views 2
row inst_stereo_ipd0 --size 1920x1080 --tests instanced --views 2 -p views.ipd=0
row light_both --size 1920x1080 --tests lighting --views 1,2
python3 -m benchmarks.vr_tests --from-json $OUT/inst_*.json $OUT/light_both.json > $OUT/stereo_probe.txt 2>&1; echo "table rc=$?"

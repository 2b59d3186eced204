#!/bin/bash
# Session 9, H200 (issue 18): where --naive-cpu loses the device on vr_instanced (size, frame
# count, validation, draw mode), then the naive columns of the other three tests.
set -u
one() { local name=$1; shift; echo "== $name: rgraph run clustered $*"; timeout 30 python3 -m rgraph run clustered --no-check-data "$@" 2>&1 | grep -v -E '^(│|┃|┏|┡|└|┗)' | tail -6; echo "rc=${PIPESTATUS[0]}"; }
{
  one small-60 --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 320x180 --frames 60 --warmup 0
  one full-1 --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 1920x1080 --frames 1 --warmup 0
  one full-3 --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 1920x1080 --frames 3 --warmup 0
  one half-30 --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 960x540 --frames 30 --warmup 0
  one full-validate-3 --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 1920x1080 --frames 3 --warmup 0 --validate
  one unique-full-30 --scene graphs/scenes/vr_unique.yaml --naive-cpu --size 1920x1080 --frames 30 --warmup 0
  one lighting-full-30 --scene graphs/scenes/lighting_test.yaml --naive-cpu --size 1920x1080 --frames 30 --warmup 0
  one instanced-stereo-small --scene graphs/scenes/vr_instanced.yaml --naive-cpu --size 320x180 --frames 30 --warmup 0 -p views=2
} > $OUT/naive_bisect.txt 2>&1; echo "bisect done"
timeout 150 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 60 --warmup 0.3 --logic-hz 60 --tests skinned,lighting,unique --modes naive --json $OUT/vr_naive3.json > $OUT/vr_naive3.txt 2>&1; echo "vr naive 3 rc=$?"

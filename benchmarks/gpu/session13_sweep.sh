#!/bin/bash
# Session 13, H200 (issue 15): rt.max_depth 1..8 against a depth-16 reference with `rgraph sweep`
# (accuracy vs GPU time), stand-alone and hybrid, living room camera 1 and conference camera 3,
# 1280x720. Run from a checkout: source .gl/enter.sh first. Writes under $OUT.
set -u
mkdir -p $OUT/sweep
for g in rt_standalone rt_hybrid; do
  for sc in "rt_living_room 1" "rt_conference 3"; do
    set -- $sc
    timeout 280 python3 -m rgraph sweep $g --scene graphs/scenes/$1.yaml --camera $2 --knob rt.max_depth=1,2,3,4,5,6,7,8 \
      --reference rt.max_depth=16 --metric psnr --size 1280x720 --frames 10 --warmup 0.3 --no-progress \
      -o $OUT/sweep/${g}_$1 > $OUT/sweep/${g}_$1.txt 2>&1; echo "$g $1 rc=$?"
    rm -rf $OUT/sweep/${g}_$1/images $OUT/sweep/${g}_$1/errors
  done
done
tar czf $OUT/sweep.tgz -C $OUT sweep && rm -rf $OUT/sweep

#!/bin/bash
# Session 13, H200 (issue 15): where conference's frame goes. Stand-alone and hybrid side by side
# (benchmarks.hybrid_rt) as bundled at rt.max_depth 4 and 1 (depth 1: no reflection/refraction
# trees), and with no lights (benchmarks/graphs/rt_conference_dark.yaml: no shadow rays).
# Run from a checkout: source .gl/enter.sh first. Writes under $OUT.
set -u
mkdir -p $OUT/probe
run() { name=$1; shift; timeout 240 python3 -m benchmarks.hybrid_rt --frames 10 --no-raster --json $OUT/probe/$name.jsonl "$@" > $OUT/probe/$name.md 2>$OUT/probe/$name.err; echo "$name rc=$?"; }
run conf_d4 --scenes rt_conference
run conf_d1 --scenes rt_conference --max-depth 1
run conf_dark_d4 --scenes benchmarks/graphs/rt_conference_dark.yaml
run conf_dark_d1 --scenes benchmarks/graphs/rt_conference_dark.yaml --max-depth 1
tar czf $OUT/probe.tgz -C $OUT probe && rm -rf $OUT/probe

#!/bin/bash
# Session 9, H200 host: compile speed (issue 19) and sweep throughput with workers drawing their
# own error maps (issue 21 recheck). Writes under $OUT.
set -u
timeout 200 python3 benchmarks/compile_scaling.py --sizes 250,1000,4000,16000 --chain 10000 --side-effects 5000 --phases > $OUT/compile_scaling.txt 2>&1; echo "compile rc=$?"
timeout 300 python3 benchmarks/sweep_throughput.py --size 1280x720 --frames 10 --groups hbao,sss,rt,clusters --pools 4x8,8x8 -o /tmp/tp --json $OUT/sweep_throughput.json > $OUT/sweep_throughput.txt 2>&1; echo "sweep rc=$?"

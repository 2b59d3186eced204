#!/bin/bash
# Session 10, H200 (issue 18): draw.order none against front_to_back, the four VR tests, mono
# and stereo, GPU-driven, one VkQueue, no logic thread (each row its own process).
# Run from a checkout: source .gl/enter.sh first.
set -u
for order in none front_to_back; do
  timeout 200 python3 -m benchmarks.vr_tests --size 1920x1080 --frames 40 --warmup 0.3 --modes gpu --queues one -p draw.order=$order --json $OUT/order_$order.json > $OUT/order_$order.txt 2>&1; echo "$order rc=$?"
done

#!/bin/bash
# Session 15, H200: the merged runtime changes (ray-query features enabled where offered, the
# multiview sort-last composite, the timestamp slack) on NVIDIA, under validation where the
# layer allows (its 1.3.239 crashes in vkCreateRayTracingPipelinesKHR, so rgraph refuses
# --validate with raytrace passes: those run without it). Expected: rc 0 everywhere but the
# ray-query probe, refused by name (rc 2: the H200 has no VK_KHR_ray_query).
# Run from a checkout: source .gl/enter.sh first. Writes under $OUT.
set -u
mkdir -p $OUT/smoke
run() { name=$1; shift; timeout 240 python3 -c 'import sys; from rgraph.cli import main; sys.exit(main(sys.argv[1:]))' "$@" > $OUT/smoke/$name.out 2>&1; echo "$name rc=$? $(grep -ci 'validation' $OUT/smoke/$name.out) lines naming validation"; }
run surgery run surgery --size 320x180 --frames 3 --validate --out $OUT/smoke/surgery.png
run rt_hybrid run rt_hybrid --scene graphs/scenes/rt_conference.yaml --camera 3 --size 320x180 --frames 3 --out $OUT/smoke/rt_hybrid.png
run rt_standalone run rt_standalone --scene graphs/scenes/rt_conference.yaml --camera 3 --size 320x180 --frames 3 --out $OUT/smoke/rt_standalone.png
run clustered_stereo run clustered --scene graphs/scenes/vr_instanced.yaml -p views=2 --size 320x180 --frames 3 --validate --out $OUT/smoke/stereo.png
run stereo_split run clustered -p views=2 --devices 0,0 --split sort-last --size 320x180 --frames 3 --validate --out $OUT/smoke/split.png
run stereo_split_batched run clustered -p views=2 --devices 0,0 --split sort-last --size 320x180 --frames 3 --out $OUT/smoke/split_batched.png
run ray_query_probe run tests/fixtures/unseen/graphs/rt_ray_query_compute.yaml --size 64x48 --frames 2 --validate

#!/bin/bash
# Session 9, H200 (issue 15): the hybrid with every ray tree walked in-thread by the one shade
# dispatch (rt.wavefront=0, the study's design: one full-screen pass from the G-buffer that calls
# traceRay only where the material reflects or refracts) against the stand-alone, one process per
# scene; then the async-shading variant on the gallery. Writes under $OUT; fits one 10-minute call.
set -u
for s in rt_living_room rt_conference rt_gallery; do
  timeout 120 python3 -m benchmarks.hybrid_rt --scenes $s --frames 10 --no-raster --param rt.wavefront=0 --json $OUT/inthread_$s.jsonl > $OUT/inthread_$s.md 2>&1; echo "in-thread $s rc=$?"
done
timeout 150 python3 -m benchmarks.hybrid_rt --scenes rt_gallery --frames 10 --no-raster --async --json $OUT/async_rt_gallery.jsonl > $OUT/async_rt_gallery.md 2>&1; echo "async gallery rc=$?"

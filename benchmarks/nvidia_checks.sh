#!/usr/bin/env bash
# Issue 3's GPU checks in one call (run on the GPU machine after `source .gl/enter.sh`):
# bundled graphs under validation with data checks, a fuzz batch, per-pass times and frame CPU.
# Writes logs under $OUT (default ./nvidia-out).
set -u
OUT=${OUT:-nvidia-out}
mkdir -p "$OUT"
nvidia-smi -L > "$OUT/device.txt" 2>&1
for spec in "surgery 1920x1080" "surgery 64x64" "graphs/allocator_lines.yaml 256x256"; do
  set -- $spec
  name=$(basename "$1" .yaml)
  echo "== rgraph run $1 --validate --frames 4 --size $2" >> "$OUT/validate.txt"
  timeout 300 python3 -m rgraph run "$1" --validate --frames 4 --size "$2" >> "$OUT/validate.txt" 2>&1
  echo "rc=$?" >> "$OUT/validate.txt"
done
echo "== rgraph run surgery --validate --sync naive" >> "$OUT/validate.txt"
timeout 300 python3 -m rgraph run surgery --validate --frames 4 --size 1920x1080 --sync naive >> "$OUT/validate.txt" 2>&1
echo "rc=$?" >> "$OUT/validate.txt"
RGRAPH_FUZZ_EXAMPLES=${FUZZ:-24} timeout 400 python3 -m pytest -q -p no:cacheprovider \
  tests/test_run_fuzz.py tests/test_naive_sync.py > "$OUT/fuzz.txt" 2>&1
echo "rc=$?" >> "$OUT/fuzz.txt"
timeout 300 python3 -m rgraph run surgery --frames 100 --size 1920x1080 --timings "$OUT/t1080.json" > "$OUT/t1080.txt" 2>&1
timeout 300 python3 benchmarks/frame_cpu.py --frames 2000 --busy-frames 300 > "$OUT/frame_cpu.txt" 2>&1
timeout 300 python3 benchmarks/frame_cpu.py --frames 2000 --passes real --size 1920x1080 --busy-frames 100 > "$OUT/frame_cpu_real.txt" 2>&1

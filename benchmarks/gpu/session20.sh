#!/bin/bash
# Session 20 (issues 15 and 18): the figures of the code as it stands, on whatever card the call
# gets. PART=rt: Table 3 (benchmarks.hybrid_rt, --no-raster, 10 frames), one process per scene,
# SM clocks logged around each. PART=vr: benchmarks.vr_tests at 1920x1080, GPU-driven and
# --naive-cpu, mono and stereo, logic at 60 Hz, one VkQueue, each row its own process.
# PART=stereo (session 21): the three surgery graphs at 1920x1080, views=1 then views=2, 60 frames
# each after 0.3 s of warm-up, one process per run, alternated mono/stereo three times.
# PART=validate (session 21): the ray tracing graphs and surgery under --validate on the card,
# with the layer setup installs here, packed first with
#   mkdir -p .gl-vvl && tar cJf .gl-vvl/layer.tar.xz -C .venv/share/rgraph/vulkan-layers .
# and carried: carry [".gl", ".whl", ".gl-vvl"] (the layer is about 6 MB packed).
# Run from a checkout: source .gl/enter.sh first. Writes under $OUT.
set -u
clocks() { nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,temperature.gpu,power.draw --format=csv,noheader >> $1 2>&1; }
case ${PART-rt} in
rt)
  mkdir -p $OUT/rt
  for s in ${SCENES-rt_living_room rt_conference rt_gallery}; do
    clocks $OUT/rt/clocks.txt
    timeout ${SCENE_TIMEOUT-150} python3 -m benchmarks.hybrid_rt --scenes $s --frames ${FRAMES-10} --no-raster ${RT_FLAGS-} \
      --json $OUT/rt/table_$s.jsonl > $OUT/rt/table_$s.md 2>$OUT/rt/table_$s.err; echo "table $s rc=$?"
  done
  clocks $OUT/rt/clocks.txt ;;
vr)
  mkdir -p $OUT/vr
  clocks $OUT/vr/clocks.txt; uptime > $OUT/vr/load.txt
  timeout ${VR_TIMEOUT-420} python3 -m benchmarks.vr_tests --size 1920x1080 --frames ${FRAMES-120} --warmup 0.3 \
    --logic-hz 60 --modes ${MODES-gpu,naive} --queues one --json $OUT/vr/vr.json > $OUT/vr/vr.txt 2>&1
  echo "vr rc=$?"; clocks $OUT/vr/clocks.txt; uptime >> $OUT/vr/load.txt ;;
stereo)
  mkdir -p $OUT/stereo
  for round in 1 2 3; do
    for g in surgery surgery_clustered async_overlap; do
      for views in 1 2; do
        clocks $OUT/stereo/clocks.txt
        timeout ${RUN_TIMEOUT-120} python3 -m rgraph run $g --size 1920x1080 --frames 60 --warmup 0.3 -p views=$views \
          --timings $OUT/stereo/${g}_v${views}_r$round.json > $OUT/stereo/${g}_v${views}_r$round.txt 2>&1
        echo "$g views=$views round $round rc=$?"
      done
    done
  done ;;
validate)
  mkdir -p $OUT/validate /tmp/vvl && tar xJf .gl-vvl/layer.tar.xz -C /tmp/vvl && export VK_LAYER_PATH=/tmp/vvl
  for run in "rt_standalone --scene graphs/scenes/rt_tiny.yaml" "rt_hybrid --scene graphs/scenes/rt_tiny.yaml" \
             "rt_hybrid_raster --scene graphs/scenes/rt_tiny.yaml" "rt_hybrid --scene graphs/scenes/rt_conference.yaml" \
             "surgery" "clustered -p views=2"; do
    name=$(echo $run | tr ' /' '__')
    timeout ${RUN_TIMEOUT-120} python3 -m rgraph run $run --size 320x180 --frames 3 --validate \
      > $OUT/validate/$name.txt 2>&1; echo "$run rc=$? $(grep -o 'rgraph: [0-9]* validation message.*' $OUT/validate/$name.txt)"
  done ;;
esac

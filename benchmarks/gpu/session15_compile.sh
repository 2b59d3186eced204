#!/usr/bin/env bash
# Compile speed on the GPU machine's CPU with the compiled accelerators (issue 19).
# That machine runs Python 3.12 without build tools, so its extensions are built here first:
#   bash benchmarks/gpu/session15_compile.sh build    # needs python3.12 with Cython and setuptools
# (PY312=/path/to/python3.12 to choose it); it writes .whl/native312.tar (carried with .whl). Then,
# on the GPU machine (carry .gl and .whl):
#   source .gl/enter.sh && bash benchmarks/gpu/session15_compile.sh run
# Output under $OUT: plan fingerprints with and without the accelerators (must be equal) and
# compile_scaling.py's rows both ways.
set -euo pipefail
case "${1:-run}" in
  build)
    py=${PY312:-python3.12}
    tmp=$(mktemp -d)
    git worktree add -f -q --detach "$tmp" HEAD
    (cd "$tmp" && "$py" setup.py -q build_ext --inplace >/dev/null)
    mkdir -p .whl
    (cd "$tmp" && tar cf - $(find rgraph -name '*cpython-312*.so')) > .whl/native312.tar
    git worktree remove --force "$tmp"
    echo "wrote .whl/native312.tar"
    ;;
  run)
    out=${OUT:-out}
    mkdir -p "$out"
    tar xf .whl/native312.tar
    python3 -W error::RuntimeWarning -c 'from rgraph.compiler import phases; assert phases.SYNC_NATIVE is not None'
    python3 benchmarks/plan_fingerprints.py > "$out/fp_native.txt"
    RGRAPH_NATIVE=0 python3 benchmarks/plan_fingerprints.py > "$out/fp_python.txt"
    cmp "$out/fp_native.txt" "$out/fp_python.txt"
    python3 benchmarks/compile_scaling.py --phases --repeats 40 | tee "$out/scaling_native.txt"
    RGRAPH_NATIVE=0 python3 benchmarks/compile_scaling.py --sizes 1000 --chain 0 --side-effects 0 --phases \
      --repeats 40 | tee "$out/scaling_python.txt"
    ;;
  *) echo "usage: $0 build|run" >&2; exit 2 ;;
esac

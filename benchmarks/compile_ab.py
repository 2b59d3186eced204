"""Compile the same random graph in several checkouts, alternating one compile at a time.

    .venv/bin/python benchmarks/compile_ab.py CHECKOUT [CHECKOUT ...] [--passes 1000] [--rounds 100]

Each checkout gets a worker process (its own ``.venv/bin/python``, its own rgraph) that
loads the graph of ``compile_scaling.py``'s random row once; then each round asks every
worker in turn for one whole compile (``compile_plan``) and one compile phase by phase
(``rgraph.compiler.phases.PHASES``, the placement search inside ``place`` timed apart, as
``compile_scaling.py --phases`` does). Printed: the minimum CPU ms of each over the rounds.
On a shared machine a load that comes and goes then hits every checkout alike, where
whole runs of ``compile_scaling.py`` one after the other can each meet a different load.
``--fresh``: each compile gets a freshly specialized spec (new objects: memo tables keyed by
spec objects start cold), the way a graph that changed is compiled.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve()


def worker(passes: int, fresh: bool) -> None:
    """Answer 'whole' and 'phases' lines on stdin with one compile's CPU ms."""
    import gc
    import tempfile

    sys.path.insert(0, str(Path.cwd()))  # the checkout it runs in
    import rgraph.memory
    from rgraph.compiler.phases import PHASES, Compilation
    from rgraph.compiler.pipeline import DEFAULT_PROFILE, _default_provider, compile_plan, frontend
    from rgraph.random_graph import random_graph, to_yaml

    tmp = tempfile.TemporaryDirectory()
    path = Path(tmp.name) / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=passes, passes=passes)))
    spec = frontend(path, size=(16, 16)).spec
    search, spent = rgraph.memory.place, [0.0]

    def timed_search(*args, **kwargs):
        start = time.process_time()
        try:
            return search(*args, **kwargs)
        finally:
            spent[0] += time.process_time() - start

    compile_plan(spec)
    print("ready", flush=True)
    for line in sys.stdin:
        if fresh:
            spec = frontend(path, size=(16, 16)).spec
        if line.strip() == "whole":
            start = time.process_time()
            compile_plan(spec)
            print(f"whole={(time.process_time() - start) * 1e3:.4f}", flush=True)
        elif line.strip() == "phases":
            enabled = gc.isenabled()
            gc.disable()  # as in pipeline.compilation
            rgraph.memory.place, spent[0] = timed_search, 0.0
            c = Compilation(spec, "aliased", _default_provider(), DEFAULT_PROFILE)
            out = []
            for name, phase in PHASES:
                start = time.process_time()
                c = phase(c)
                out.append(f"{name}={(time.process_time() - start) * 1e3:.4f}")
            rgraph.memory.place = search
            del c
            if enabled:
                gc.enable()
            print(" ".join([*out, f"placement_search={spent[0] * 1e3:.4f}"]), flush=True)
        else:
            tmp.cleanup()
            return


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("checkouts", nargs="*", type=Path)
    parser.add_argument("--passes", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=100)
    parser.add_argument("--fresh", action="store_true", help="a freshly specialized spec for every compile")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.passes, args.fresh)
        return
    workers = []
    for checkout in args.checkouts:
        proc = subprocess.Popen([str(checkout / ".venv" / "bin" / "python"), str(HERE), "--worker", "--passes",
                                 str(args.passes), *(["--fresh"] if args.fresh else [])], cwd=checkout, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                text=True)
        assert proc.stdin is not None and proc.stdout is not None
        if proc.stdout.readline().strip() != "ready":
            sys.exit(f"{checkout}: the worker did not start")
        workers.append(proc)
    best: list[dict[str, float]] = [{} for _ in workers]
    for _ in range(args.rounds):
        for request in ("whole", "phases"):
            for k, proc in enumerate(workers):
                assert proc.stdin is not None and proc.stdout is not None
                proc.stdin.write(request + "\n")
                proc.stdin.flush()
                for item in proc.stdout.readline().split():
                    name, value = item.split("=")
                    best[k][name] = min(best[k].get(name, math.inf), float(value))
    for proc in workers:
        assert proc.stdin is not None
        proc.stdin.close()
        proc.wait()
    names = list(dict.fromkeys(name for b in best for name in b if name != "whole")) + ["whole"]
    print(f"min cpu ms over {args.rounds} rounds, {args.passes}-pass random graph"
          + (", a fresh spec each compile" if args.fresh else ""))
    print(f"{'':18s}" + "".join(f"{str(c):>28s}" for c in args.checkouts))
    for name in names:
        print(f"{name:18s}" + "".join(f"{b[name]:28.2f}" if name in b else f"{'-':>28s}" for b in best))


if __name__ == "__main__":
    main()

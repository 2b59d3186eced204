"""Median compile time (parsed spec -> plan) for random graphs of 250 .. 16k passes.

    .venv/bin/python benchmarks/compile_scaling.py [--sizes 250,1000,4000,16000] [--policy aliased]
        [--chain 10000] [--side-effects 5000] [--phases] [--repeats N]

Prints one row per size (wall median, CPU minimum and median) and the growth exponent fitted on log(time) vs log(passes) (of the
wall medians and of the minimum CPU times: on a shared machine the second is steadier), then
two structured graphs: a chain (pass i reads buffer b_i and writes b_{i+1}: every buffer
reuses the memory of the one before) and one with N side-effect buffers (each written by
its own pass, all kept as outputs). Target (issue 19): 1,000 random passes in at most
16 ms; exponent at most 1.15; the 10,000-resource chain in at most 1 s.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rgraph.compiler.pipeline import compile_plan, frontend  # noqa: E402
from rgraph.plan import Plan  # noqa: E402
from rgraph.random_graph import random_graph, to_yaml  # noqa: E402
from rgraph.spec.specialize import Spec  # noqa: E402


def timed(spec: Spec, policy: str, repeats: int) -> tuple[float, float, float, Plan]:
    """Median wall time, minimum CPU time and median CPU time (process time: less disturbed by
    other jobs on a shared machine) of ``repeats`` compiles of ``spec``, and the plan."""
    wall, cpu = [], []
    plan = None
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        plan = compile_plan(spec, policy=policy)
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    assert plan is not None
    return statistics.median(wall), min(cpu), statistics.median(cpu), plan


def phase_times(spec: Spec, policy: str, repeats: int) -> dict[str, float]:
    """Minimum CPU seconds of each compiler phase (``rgraph.compiler.phases.PHASES``), and of
    the placement search inside ``place`` (``rgraph.memory.place``, key ``placement search``)."""
    import gc

    import rgraph.memory
    from rgraph.compiler.phases import PHASES, Compilation
    from rgraph.compiler.pipeline import DEFAULT_PROFILE, _default_provider

    best: dict[str, float] = {}
    search = rgraph.memory.place
    spent = [0.0]

    def timed_search(*args, **kwargs):
        start = time.process_time()
        try:
            return search(*args, **kwargs)
        finally:
            spent[0] += time.process_time() - start

    enabled = gc.isenabled()
    gc.disable()  # as in pipeline.compilation
    rgraph.memory.place = timed_search  # looked up at each call (rgraph.compiler.memory.place_resources)
    try:
        for _ in range(repeats):
            c = Compilation(spec, policy, _default_provider(), DEFAULT_PROFILE)
            spent[0] = 0.0
            for name, phase in PHASES:
                start = time.process_time()
                c = phase(c)
                best[name] = min(best.get(name, math.inf), time.process_time() - start)
            best["placement search"] = min(best.get("placement search", math.inf), spent[0])
    finally:
        rgraph.memory.place = search
        if enabled:
            gc.enable()
    return best


def phases_line(spec: Spec, policy: str, repeats: int) -> str:
    times = phase_times(spec, policy, repeats)
    search = times.pop("placement search")
    return "  phases, min cpu ms: " + ", ".join(f"{name} {seconds * 1e3:.1f}" for name, seconds in times.items()) + \
        f" (of place: placement search {search * 1e3:.1f})"


def measure(passes: int, policy: str, repeats: int) -> tuple[float, float, float, int, int, Spec]:
    graph = random_graph(seed=passes, passes=passes)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "g.yaml"
        path.write_text(to_yaml(graph))
        spec = frontend(path, size=(16, 16)).spec
    median, cpu, median_cpu, plan = timed(spec, policy, repeats)
    return median, cpu, median_cpu, len(plan.passes), plan.stats.barriers, spec


def chain_yaml(count: int) -> str:
    """Pass i reads b_i and writes b_{i+1} (pass 0 writes b_1); b_count is the output."""
    lines = ["rgraph: 1", "name: chain", "resources:"]
    lines += [f"  b{i}: {{kind: buffer, bytes: 256}}" for i in range(1, count + 1)]
    lines.append("passes:")
    lines.append("  p0: {kind: compute, writes: {b1: storage_write}}")
    lines += [f"  p{i}: {{kind: compute, reads: {{b{i}: storage_read}}, writes: {{b{i + 1}: storage_write}}}}"
              for i in range(1, count)]
    lines.append(f"outputs: [b{count}]")
    return "\n".join(lines) + "\n"


def side_effects_yaml(count: int) -> str:
    """``count`` passes, each writing its own buffer, every buffer an output."""
    lines = ["rgraph: 1", "name: side_effects", "resources:"]
    lines += [f"  s{i}: {{kind: buffer, bytes: 256}}" for i in range(count)]
    lines.append("passes:")
    lines += [f"  p{i}: {{kind: compute, writes: {{s{i}: storage_write}}}}" for i in range(count)]
    lines.append("outputs: [" + ", ".join(f"s{i}" for i in range(count)) + "]")
    return "\n".join(lines) + "\n"


def measure_text(text: str, policy: str, repeats: int) -> tuple[float, float, int, Spec]:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "g.yaml"
        path.write_text(text)
        spec = frontend(path, size=(16, 16)).spec
    median, cpu, _, plan = timed(spec, policy, repeats)
    return median, cpu, len(plan.passes), spec


def fresh_ms(passes: int, policy: str, specs: int = 5) -> tuple[float, float]:
    """Median wall ms and minimum CPU ms of the first compile of each of ``specs`` freshly
    specialized specs of the same random graph (new objects each time: the compiler's memo
    tables, keyed by interned values and by spec objects, start cold for that spec)."""
    wall, cpu = [], []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "g.yaml"
        path.write_text(to_yaml(random_graph(seed=passes, passes=passes)))
        for _ in range(specs):
            spec = frontend(path, size=(16, 16)).spec
            start, start_cpu = time.perf_counter(), time.process_time()
            compile_plan(spec, policy=policy)
            wall.append(time.perf_counter() - start)
            cpu.append(time.process_time() - start_cpu)
    return statistics.median(wall) * 1e3, min(cpu) * 1e3


def cache_hit_us(passes: int, repeats: int = 200) -> float:
    """Median time of an unchanged recompile through ``PlanCache`` (after one miss)."""
    from rgraph.compiler.cache import PlanCache

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "g.yaml"
        path.write_text(to_yaml(random_graph(seed=passes, passes=passes)))
        cache = PlanCache()
        cache.plan(path, size=(16, 16))
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            cache.plan(path, size=(16, 16))
            times.append(time.perf_counter() - start)
    return statistics.median(times) * 1e6


def incremental_ms(repeats: int = 20) -> tuple[float, float]:
    """Median ms of a surgery "recompile" through ``PlanCache`` after a value-only param
    changed (a new ``hbao.strength`` each time: the incremental path), and of a full compile."""
    from rgraph.compiler.cache import PlanCache
    from rgraph.compiler.pipeline import compile_graph_plan

    cache = PlanCache()
    cache.plan("surgery", size=(64, 64))
    times, full = [], []
    for k in range(repeats):
        start = time.perf_counter()
        cache.plan("surgery", params={"hbao.strength": f"{1 + k / 100}"}, size=(64, 64))
        times.append(time.perf_counter() - start)
        start = time.perf_counter()
        compile_graph_plan("surgery", params={"hbao.strength": f"{1 + k / 100}"}, size=(64, 64))
        full.append(time.perf_counter() - start)
    assert cache.reused == repeats
    return statistics.median(times) * 1e3, statistics.median(full) * 1e3


def exponent(points: list[tuple[int, float]]) -> float:
    """Least-squares slope of log(time) over log(passes)."""
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(t) for _, t in points]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum((x - mx) ** 2 for x in xs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", default="250,1000,4000,16000")
    parser.add_argument("--policy", default="aliased")
    parser.add_argument("--chain", type=int, default=10000, help="resources of the chain graph (0: skip)")
    parser.add_argument("--side-effects", type=int, default=5000, help="side-effect buffers (0: skip)")
    parser.add_argument("--phases", action="store_true", help="also the minimum CPU time of each compiler phase")
    parser.add_argument("--repeats", type=int, default=0,
                        help="compiles per random graph size (default: 3-15, fewer for larger graphs)")
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    rows = []
    print(f"{'passes':>8} {'executed':>9} {'barriers':>9} {'median ms':>10} {'us/pass':>8} {'min cpu ms':>11}"
          f" {'median cpu ms':>14}")
    for n in sizes:
        repeats = args.repeats or max(3, min(15, 16000 // n))
        median, cpu, median_cpu, executed, barriers, spec = measure(n, args.policy, repeats)
        rows.append((n, median, cpu))
        print(f"{n:>8} {executed:>9} {barriers:>9} {median * 1e3:>10.1f} {median / n * 1e6:>8.1f} {cpu * 1e3:>11.1f}"
              f" {median_cpu * 1e3:>14.1f}")
        if args.phases:
            print(phases_line(spec, args.policy, repeats))
    if len(rows) > 1:
        print(f"growth exponent: {exponent([(n, t) for n, t, _ in rows]):.2f} (wall medians), "
              f"{exponent([(n, c) for n, _, c in rows]):.2f} (min cpu)  (policy {args.policy})")
    for label, count, text in (("chain", args.chain, chain_yaml), ("side-effect buffers", args.side_effects,
                                                                      side_effects_yaml)):
        if count:
            median, cpu, executed, spec = measure_text(text(count), args.policy, repeats=3)
            print(f"{label} of {count}: {executed} passes, median {median * 1e3:.1f} ms (min cpu {cpu * 1e3:.1f} ms)")
            if args.phases:
                print(phases_line(spec, args.policy, 3))
    if 1000 in sizes:
        wall, cpu = fresh_ms(1000, args.policy)
        print(f"first compile of a freshly specialized 1,000-pass spec (5 specs): median {wall:.1f} ms "
              f"(min cpu {cpu:.1f} ms)")
    if args.repeats:
        return  # a phase comparison: no cache figures
    print(f"unchanged 1,000-pass graph through PlanCache: median {cache_hit_us(1000):.1f} us")
    reuse, full = incremental_ms()
    print(f"surgery with a changed value-only param through PlanCache: median {reuse:.1f} ms "
          f"(full load + compile: {full:.1f} ms)")


if __name__ == "__main__":
    main()

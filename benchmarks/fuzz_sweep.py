"""A batch of random graphs on the default device under validation + synchronization
validation with data checks, spread over worker processes, within a time budget.

Graph ``i`` of the batch is ``random_graph(seed, passes)`` with ``seed = start + i`` and passes
and policy drawn from ``random.Random(seed)`` (1..max_passes, dedicated or aliased), so every
report names a reproducible case (``benchmarks/nvidia_seed.py SEED PASSES POLICY OUT``, or the
regression list of tests/test_run_fuzz.py). Plans are compiled with the live device's memory
requirements, as the fuzz tests do. Prints one line per failing graph and a summary; writes every
result as JSON lines under ``--out``; exits 1 if any graph failed.

    python benchmarks/fuzz_sweep.py [--start 0] [--count 1000] [--workers 8]
        [--max-passes 40] [--seconds 500] [--out fuzz-out] [--seeds 156,333]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import random
import sys
import tempfile
import time
from contextlib import ExitStack
from pathlib import Path
from typing import Any

POLICIES = ("dedicated", "aliased")
_worker: dict[str, Any] = {}


def case(seed: int, max_passes: int) -> tuple[int, int, str]:
    """The (seed, passes, policy) of batch entry ``seed``."""
    rng = random.Random(seed)
    return seed, rng.randint(1, max_passes), rng.choice(POLICIES)


def _open_worker() -> None:
    """Open the worker's device (validation on) once: memory requirements and every case's run;
    a failure is kept and reported with every case (an initializer that raises makes the pool
    respawn workers forever)."""
    import rgraph

    stack = ExitStack()
    try:
        gpu = stack.enter_context(rgraph.open_device(validate=True, verbose=False))
        memory = gpu.memory_requirements()
    except Exception as exc:  # noqa: BLE001 - reported per case by run_case
        _worker.update(error=f"worker could not open the device: {type(exc).__name__}: {exc}")
        return
    _worker.update(stack=stack, gpu=gpu, memory=memory, tmp=Path(tempfile.mkdtemp(prefix="rgraph-fuzz-")))


def run_case(entry: tuple[int, int, str]) -> dict[str, Any]:
    """Compile and run one graph; its messages, data check and any exception."""
    from rgraph.compiler.pipeline import compile_spec, frontend
    from rgraph.random_graph import random_graph, to_yaml

    seed, passes, policy = entry
    record: dict[str, Any] = {"seed": seed, "passes": passes, "policy": policy}
    started = time.perf_counter()
    if "error" in _worker:
        return record | {"messages": [], "data_ok": False, "error": _worker["error"], "ok": False, "seconds": 0.0}
    try:
        path = _worker["tmp"] / f"g_{seed}_{passes}.yaml"
        path.write_text(to_yaml(random_graph(seed, passes)))
        plan = compile_spec(frontend(path, size=(16, 16)).spec, policy=policy, memory_provider=_worker["memory"])
        result = _worker["gpu"].load(plan).run_and_check(2, check_data=True)
        record.update(messages=[str(m) for m in result.messages], data_ok=result.data_ok,
                      mismatches=[str(m) for m in result.mismatches[:5]])
    except Exception as exc:  # noqa: BLE001 - a crash is a finding, reported with the case
        record.update(messages=[], data_ok=False, error=f"{type(exc).__name__}: {exc}")
    record["ok"] = not record["messages"] and record["data_ok"] is True and "error" not in record
    record["seconds"] = round(time.perf_counter() - started, 3)
    return record


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default=None, help="comma-separated seeds instead of --start/--count")
    parser.add_argument("--start", type=int, default=0)
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=8)
    parser.add_argument("--max-passes", type=int, default=40)
    parser.add_argument("--seconds", type=float, default=500.0, help="stop taking new graphs after this")
    parser.add_argument("--out", type=Path, default=Path("fuzz-out"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    seeds = ([int(x) for x in args.seeds.split(",")] if args.seeds
             else list(range(args.start, args.start + args.count)))
    entries = [case(seed, args.max_passes) for seed in seeds]
    deadline = time.perf_counter() + args.seconds
    done: list[dict[str, Any]] = []
    with (args.out / "results.jsonl").open("w") as log, \
            multiprocessing.get_context("spawn").Pool(args.workers, initializer=_open_worker) as pool:
        results = pool.imap_unordered(run_case, entries)
        while True:
            try:
                record = results.next(timeout=max(1.0, deadline - time.perf_counter()))
            except (StopIteration, multiprocessing.TimeoutError):
                pool.terminate()
                break
            done.append(record)
            log.write(json.dumps(record) + "\n")
            log.flush()
            if not record["ok"] and sum(not r["ok"] for r in done) <= 50:  # the rest: results.jsonl
                first = (record["messages"] or record.get("mismatches") or [record.get("error", "")])[:1]
                print(f"FAIL seed {record['seed']}/{record['passes']} {record['policy']}: "
                      f"{len(record['messages'])} messages, data_ok={record['data_ok']}; {first[0][:400] if first else ''}",
                      flush=True)
            if time.perf_counter() > deadline:
                pool.terminate()
                break
    failed = [r for r in done if not r["ok"]]
    passes = sorted(r["passes"] for r in done)
    print(f"{len(done)} graphs (seeds {seeds[0]}..{seeds[-1]}, {args.workers} workers, "
          f"passes 1..{args.max_passes}, median {passes[len(passes) // 2] if passes else 0}): "
          f"{len(done) - len(failed)} clean, {len(failed)} failed")
    return 1 if failed or not done else 0


if __name__ == "__main__":
    sys.exit(main())

"""A batch of random graphs on the default device under validation + synchronization
validation with data checks, spread over worker processes (local ones, or Ray tasks with
``--ray``: rgraph.sweep.parallel), within a time budget.

Graph ``i`` of the batch is ``random_graph(seed, passes)`` with ``seed = start + i`` and passes
and policy drawn from ``random.Random(seed)`` (1..max_passes, dedicated or aliased), so every
report names a reproducible case (``benchmarks/nvidia_seed.py SEED PASSES POLICY OUT``, or the
regression list of tests/test_run_fuzz.py). Plans are compiled with the live device's memory
requirements, as the fuzz tests do. Prints one line per failing graph and a summary; writes every
result as JSON lines under ``--out``; exits 1 if any graph failed.

Every ``--chunk`` graphs run in a fresh worker process (a lost worker's chunk is retried once,
then its graphs are reported as failed), so no process makes more driver instances than the
NVIDIA driver allows (~40).

    python benchmarks/fuzz_sweep.py [--start 0] [--count 1000] [--workers 8 | --ray [ADDRESS]]
        [--chunk 16] [--max-passes 40] [--seconds 500] [--out fuzz-out] [--seeds 156,333]
"""

from __future__ import annotations

import argparse
import json
import random
import sys
import tempfile
import time
from contextlib import ExitStack
from pathlib import Path
from typing import Any

POLICIES = ("dedicated", "aliased")


def case(seed: int, max_passes: int) -> tuple[int, int, str]:
    """The (seed, passes, policy) of batch entry ``seed``."""
    rng = random.Random(seed)
    return seed, rng.randint(1, max_passes), rng.choice(POLICIES)


def run_chunk(entries: list[tuple[int, int, str]]) -> list[dict[str, Any]]:
    """One worker process's cases: the device is opened once for memory requirements (a
    failure is reported with every case), then each graph compiled and run."""
    from rgraph.vk.memreq import live_requirements

    tmp = Path(tempfile.mkdtemp(prefix="rgraph-fuzz-"))
    with ExitStack() as stack:
        try:
            memory, _device = stack.enter_context(live_requirements())
        except Exception as exc:  # noqa: BLE001 - reported per case
            error = f"worker could not open the device: {type(exc).__name__}: {exc}"
            return [failed(entry, error) for entry in entries]
        return [run_case(entry, memory, tmp) for entry in entries]


def failed(entry: tuple[int, int, str], error: str) -> dict[str, Any]:
    seed, passes, policy = entry
    return {"seed": seed, "passes": passes, "policy": policy, "messages": [], "data_ok": False, "error": error,
            "ok": False, "seconds": 0.0}


def run_case(entry: tuple[int, int, str], memory: Any, tmp: Path) -> dict[str, Any]:
    """Compile and run one graph; its messages, data check and any exception."""
    from rgraph.compiler.pipeline import compile_spec, frontend
    from rgraph.random_graph import random_graph, to_yaml
    from rgraph.vk.executor import execute_plan

    seed, passes, policy = entry
    record: dict[str, Any] = {"seed": seed, "passes": passes, "policy": policy}
    started = time.perf_counter()
    try:
        path = tmp / f"g_{seed}_{passes}.yaml"
        path.write_text(to_yaml(random_graph(seed, passes)))
        plan = compile_spec(frontend(path, size=(16, 16)).spec, policy=policy, memory_provider=memory)
        result = execute_plan(plan, validate=True, frames=2, check_data=True)
        record.update(messages=[str(m) for m in result.messages], data_ok=result.data_ok,
                      mismatches=[str(m) for m in result.mismatches[:5]])
    except Exception as exc:  # noqa: BLE001 - a crash is a finding, reported with the case
        record.update(messages=[], data_ok=False, error=f"{type(exc).__name__}: {exc}")
    record["ok"] = not record["messages"] and record["data_ok"] is True and "error" not in record
    record["seconds"] = round(time.perf_counter() - started, 3)
    return record


def chunks(entries: list, size: int) -> list[tuple[int, list]]:
    return [(i, entries[i:i + size]) for i in range(0, len(entries), size)]


def main() -> int:
    from rgraph.sweep.parallel import make_executor

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default=None, help="comma-separated seeds instead of --start/--count")
    parser.add_argument("--start", type=int, default=0)
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=8, help="local worker processes (without --ray)")
    parser.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                        help="every chunk a Ray task in its own worker process (one GPU each on a GPU cluster)")
    parser.add_argument("--chunk", type=int, default=16,
                        help="graphs per worker process (default 16: under the NVIDIA driver's ~40 instances)")
    parser.add_argument("--max-passes", type=int, default=40)
    parser.add_argument("--seconds", type=float, default=500.0, help="stop taking new graphs after this")
    parser.add_argument("--out", type=Path, default=Path("fuzz-out"))
    args = parser.parse_args()
    if args.chunk < 1 or args.workers < 1:
        parser.error("--chunk and --workers must be at least 1")
    args.out.mkdir(parents=True, exist_ok=True)
    seeds = ([int(x) for x in args.seeds.split(",")] if args.seeds
             else list(range(args.start, args.start + args.count)))
    entries = [case(seed, args.max_passes) for seed in seeds]
    by_chunk = dict(chunks(entries, args.chunk))
    deadline = time.perf_counter() + args.seconds
    done: list[dict[str, Any]] = []
    executor = make_executor(args.workers, args.ray, use_ray=args.ray is not None)
    assert executor is not None
    with (args.out / "results.jsonl").open("w") as log, executor:
        outcomes = executor.run(run_chunk, by_chunk.items())
        for outcome in outcomes:
            records = outcome.value if outcome.ok else [failed(e, f"worker lost: {outcome.error}")
                                                        for e in by_chunk[outcome.key]]
            for record in records:
                done.append(record)
                log.write(json.dumps(record) + "\n")
                log.flush()
                if not record["ok"] and sum(not r["ok"] for r in done) <= 50:  # the rest: results.jsonl
                    first = (record["messages"] or record.get("mismatches") or [record.get("error", "")])[:1]
                    print(f"FAIL seed {record['seed']}/{record['passes']} {record['policy']}: "
                          f"{len(record['messages'])} messages, data_ok={record['data_ok']}; "
                          f"{first[0][:400] if first else ''}", flush=True)
            if time.perf_counter() > deadline:
                outcomes.close()  # cancels the chunks still running
                break
    failed_records = [r for r in done if not r["ok"]]
    passes = sorted(r["passes"] for r in done)
    print(f"{len(done)} graphs (seeds {seeds[0]}..{seeds[-1]}, {executor.description}, chunks of {args.chunk}, "
          f"passes 1..{args.max_passes}, median {passes[len(passes) // 2] if passes else 0}): "
          f"{len(done) - len(failed_records)} clean, {len(failed_records)} failed")
    return 1 if failed_records or not done else 0


if __name__ == "__main__":
    sys.exit(main())

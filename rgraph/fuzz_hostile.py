"""Hostile-input fuzzing of the command line: every bad file, plan, trace and argument must get
a clean answer (exit 2 -- or 1 for a plan with hazards --, located one-line errors, no
traceback, no terminal escapes, bounded time and memory).

Cases come from generators of the hostile classes of issue 14 (loader, locations, plans,
traces, arguments, scenes, paths), each seeded, so a failure is reproduced by its seed.
The parent imports rgraph once; each case runs in a forked child under ``resource.setrlimit``
limits (address space, CPU seconds) and a wall-clock timeout, so thousands of cases are fast.

    python -m rgraph.fuzz_hostile --cases 2000 --seed 1     # make fuzz
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import signal
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from random import Random

from rgraph.fuzz_cases import GENERATORS, Case

LOCATED = re.compile(r"^.+:\d+:\d+: error: \S")
ARGPARSE = re.compile(r"^rgraph( [\w-]+)?: error: \S")
UNSAFE = re.compile("[\x00-\x08\x0b-\x1f\x7f]")
WALL_S = 20.0
CPU_S = 15
MEMORY_BYTES = 2 << 30


@dataclass
class Outcome:
    case: Case
    code: int
    seconds: float
    stdout: str
    stderr: str
    problems: list[str] = field(default_factory=list)

    def summary(self) -> str:
        tail = self.stderr.strip().splitlines()[-3:] or self.stdout.strip().splitlines()[-2:]
        return (f"{self.case.name} (seed {self.case.seed}): {'; '.join(self.problems)} [exit {self.code}, "
                f"{self.seconds:.1f} s]\n    argv: {' '.join(self.case.argv)[:300]}\n    "
                + "\n    ".join(line[:300] for line in tail))


def _preload() -> None:
    """Import what the commands import, once, before forking (children start warm)."""
    import rgraph.check  # noqa: F401
    import rgraph.cli  # noqa: F401
    import rgraph.commands.inspect  # noqa: F401
    import rgraph.compiler.pipeline  # noqa: F401
    import rgraph.memory  # noqa: F401
    import rgraph.report.text  # noqa: F401

    try:
        import rgraph.vk.executor  # noqa: F401
    except Exception:  # noqa: BLE001 -- no Vulkan here: run cases import it themselves
        pass


def _child(case: Case, folder: Path, out: Path, err: Path) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_BYTES, MEMORY_BYTES))
    resource.setrlimit(resource.RLIMIT_CPU, (CPU_S, CPU_S))
    os.chdir(folder)
    fd_out = os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    fd_err = os.open(err, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    os.dup2(fd_out, 1)
    os.dup2(fd_err, 2)
    sys.stdout = open(1, "w", closefd=False)  # noqa: SIM115
    sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115
    code = 3
    try:
        from rgraph.cli import main

        code = main(case.argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 2
    except BaseException:  # noqa: BLE001 -- exactly what the fuzzer looks for
        import traceback

        traceback.print_exc()
        code = 3
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def run_case(case: Case, root: Path) -> Outcome:
    """Write the case's files into a fresh folder under ``root``, run it in a child, judge it."""
    folder = Path(tempfile.mkdtemp(dir=root))
    for name, data in case.files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    for name in case.fifos:
        os.mkfifo(folder / name)
    out, err = folder / ".stdout", folder / ".stderr"
    began = time.monotonic()
    pid = os.fork()
    if pid == 0:
        _child(case, folder, out, err)
    code, timed_out = _wait(pid, WALL_S)
    seconds = time.monotonic() - began
    outcome = Outcome(case, code, seconds, _read(out), _read(err))
    shutil.rmtree(folder, ignore_errors=True)
    outcome.problems = judge(outcome, timed_out)
    return outcome


def _wait(pid: int, limit: float) -> tuple[int, bool]:
    deadline = time.monotonic() + limit
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            if os.WIFSIGNALED(status):
                return -os.WTERMSIG(status), False
            return os.WEXITSTATUS(status), False
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return -signal.SIGKILL, True
        time.sleep(0.005)


def _read(path: Path) -> str:
    try:
        return path.read_bytes()[:200_000].decode("utf-8", errors="replace")
    except OSError:
        return ""


def judge(o: Outcome, timed_out: bool) -> list[str]:
    """What is wrong with the outcome (empty when the answer is clean)."""
    problems = []
    if timed_out:
        problems.append(f"no answer within {WALL_S:.0f} s")
    elif o.code < 0:
        problems.append(f"killed by signal {-o.code} (CPU or memory limit)")
    elif o.code not in o.case.codes:
        problems.append(f"exit {o.code}, expected {' or '.join(map(str, sorted(o.case.codes)))}")
    if "Traceback (most recent call last)" in o.stderr or "Traceback (most recent call last)" in o.stdout:
        problems.append("a Python traceback")
    if UNSAFE.search(o.stderr) or UNSAFE.search(o.stdout):
        problems.append("a control character reached the terminal")
    if o.code == 2 and not timed_out:
        errors = [line for line in o.stderr.splitlines() if "error:" in line]
        if not errors:
            problems.append("exit 2 without an error line")
        bad = [line for line in errors if not (LOCATED.match(line) or ARGPARSE.match(line))]
        if bad:
            problems.append(f"an error line that is not FILE:LINE:COL: error: ... ({bad[0][:80]!r})")
        if len(errors) > o.case.max_errors:
            problems.append(f"{len(errors)} error lines (at most {o.case.max_errors} expected)")
    return problems


def generate(count: int, seed: int) -> list[Case]:
    """``count`` cases cycling through every generator, each with its own seed."""
    cases = []
    for k in range(count):
        gen = GENERATORS[k % len(GENERATORS)]
        case_seed = seed * 1_000_003 + k
        case = gen(Random(case_seed))
        case.seed = case_seed
        cases.append(case)
    return cases


def run_all(count: int, seed: int) -> list[Outcome]:
    _preload()
    with tempfile.TemporaryDirectory(prefix="rgraph-hostile-") as tmp:
        return [run_case(case, Path(tmp)) for case in generate(count, seed)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=500, help="number of cases (default 500)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the case sequence (default 1)")
    args = parser.parse_args(argv)
    began = time.monotonic()
    outcomes = run_all(args.cases, args.seed)
    failed = [o for o in outcomes if o.problems]
    slowest = max(outcomes, key=lambda o: o.seconds, default=None)
    for o in failed:
        print(o.summary())
    names = sorted({o.case.name for o in outcomes})
    for name in names:
        times = [o.seconds for o in outcomes if o.case.name == name]
        print(f"  {name:<10} {len(times):5d} cases {sum(times):7.1f} s (max {max(times):.2f} s)")
    print(f"hostile inputs: {len(outcomes)} cases of {len(names)} classes, {len(failed)} failed, "
          f"{time.monotonic() - began:.1f} s"
          + (f" (slowest {slowest.case.name}: {slowest.seconds:.2f} s)" if slowest else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The README's tour runs as written from a clone-like checkout (no ../shared beside it).

Every command of the tour block runs, in order, from a copy of the repository's files
with the copy's ``rgraph`` package first on the path; sizes are made small (``--size
32x32`` on every command that compiles a graph) and sweeps use 2 frames, nothing else
changes. A command that fails fails the test; none is skipped.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from locations import ROOT

SIZE = "32x32"
COMPILING = {"validate", "compile", "inspect", "run", "sweep", "mutate"}
SHELL_OPERATORS = {">", ">>", "|", "&&"}


def tour_commands() -> list[str]:
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## A short tour"):]
    block = re.search(r"```sh\n(.*?)```", section, flags=re.S).group(1)
    commands = []
    for line in block.splitlines():
        words = shlex.split(line, comments=True)
        if words:
            commands.append(words)
    return [shlex.join(w) for w in commands]


def small(command: str) -> str:
    words = shlex.split(command)
    if words[0] == "rgraph" and words[1] in COMPILING:
        target = words[2]
        if not (words[1] == "inspect" and target.endswith(".json")):
            if "--size" in words:
                words[words.index("--size") + 1] = SIZE
            else:
                words[3:3] = ["--size", SIZE]
        if words[1] == "sweep":
            words += ["--frames", "2"]
    return " ".join(w if w in SHELL_OPERATORS else shlex.quote(w) for w in words)


def clone_like(tmp: Path) -> Path:
    """The repository's tracked and untracked-unignored files, as a clone (plus local edits) has them."""
    listed = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=ROOT, check=True,
                            capture_output=True).stdout.decode().split("\0")
    dest = tmp / "clone" / "rgraph"
    for name in filter(None, listed):
        src = ROOT / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    return dest


def test_readme_tour_runs_from_a_clone(tmp_path):
    commands = tour_commands()
    assert len(commands) >= 15 and all(c.startswith("rgraph ") for c in commands), commands
    assert not any("../shared" in c for c in commands)
    clone = clone_like(tmp_path)
    assert not (clone.parent / "shared").exists()
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    shim = bin_dir / "rgraph"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m rgraph "$@"\n')
    shim.chmod(0o755)
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}", "PYTHONPATH": str(clone)}
    where = subprocess.run([sys.executable, "-c", "import rgraph; print(rgraph.__file__)"], env=env, cwd=clone,
                           capture_output=True, text=True, check=True).stdout.strip()
    assert Path(where).is_relative_to(clone), where
    ran = []
    for command in commands:
        line = small(command)
        run = subprocess.run(["bash", "-c", line], env=env, cwd=clone, capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, f"{line}\nstdout:\n{run.stdout[-3000:]}\nstderr:\n{run.stderr[-3000:]}"
        assert "Traceback" not in run.stderr, line
        ran.append(line)
    assert len(ran) == len(commands)
    for name in ("plan.json", "dedicated.json", "early.json", "t.json", "naive.json", "out.png", "report.html",
                 "graph.svg", "mem.svg", "rgraph.bash", "sweep/sweep.csv", "trace.json"):
        assert (clone / name).is_file(), name
    assert (clone / "mem.svg").read_text().lstrip().startswith("<?xml")
    assert "<svg" in (clone / "graph.svg").read_text()[:500]

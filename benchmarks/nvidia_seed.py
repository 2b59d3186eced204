"""One random graph on the default device under validation, for investigating a fuzz report:
writes its plan (compiled for the live device) and the run's output under OUT.

    python3 benchmarks/nvidia_seed.py SEED PASSES POLICY OUT
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

from rgraph.api import compile_for_device
from rgraph.random_graph import random_graph, to_yaml


def main() -> None:
    seed, passes, policy, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], Path(sys.argv[4])
    out.mkdir(parents=True, exist_ok=True)
    graph = Path(tempfile.mkdtemp()) / f"g_{seed}_{passes}.yaml"
    graph.write_text(to_yaml(random_graph(seed, passes)))
    plan = compile_for_device(str(graph), size=(16, 16), policy=policy)
    (out / f"plan_{seed}_{passes}.json").write_text(json.dumps(plan, indent=1))
    run = subprocess.run([sys.executable, "-m", "rgraph", "run", str(graph), "--validate", "--frames", "2",
                          "--size", "16x16", "--policy", policy], capture_output=True, text=True)
    (out / f"run_{seed}_{passes}.txt").write_text(run.stdout + run.stderr)
    print(f"seed {seed}/{passes} {policy}: rc {run.returncode}; "
          + " | ".join(line[:300] for line in (run.stdout + run.stderr).splitlines() if "error" in line or "rgraph:" in line))


if __name__ == "__main__":
    main()

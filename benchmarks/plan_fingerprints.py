"""One line per compile: graph, policy and a hash of the plan's canonical JSON.

    python3 benchmarks/plan_fingerprints.py > after.txt      # in each checkout, then diff

Run it in two checkouts (e.g. before and after a compiler speed-up) and ``diff`` the
outputs: equal lines mean byte-identical plans. Graphs: 60 random graphs of 5-150 passes
under ``aliased``, ``dedicated``, ``optimal`` and ``tlsf``; random graphs of 300 and 1,000
passes, a 300-buffer chain and 300 side-effect buffers (``benchmarks/compile_scaling.py``);
every bundled graph at 64x64 under ``aliased`` and ``optimal``. Generated graphs are written
to one fixed folder (``--tmp``) because a plan records its source path.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

sys.path.insert(0, str(Path.cwd()))  # the checkout it is run from, not an installed rgraph
sys.path.insert(1, str(Path(__file__).resolve().parent))

from compile_scaling import chain_yaml, side_effects_yaml  # noqa: E402

from rgraph.compiler.pipeline import compile_plan, frontend  # noqa: E402
from rgraph.plan import dump  # noqa: E402
from rgraph.random_graph import random_graph, to_yaml  # noqa: E402

POLICIES = ("aliased", "dedicated", "optimal", "tlsf")


def digest(plan) -> str:
    return hashlib.sha1(dump(plan).encode()).hexdigest()[:12]


def generated() -> list[tuple[str, str]]:
    jobs = [(f"rand{seed}", to_yaml(random_graph(seed=seed, passes=5 + (seed * 37) % 146))) for seed in range(60)]
    jobs += [(f"rand_big{n}", to_yaml(random_graph(seed=n, passes=n))) for n in (300, 1000)]
    return jobs + [("chain300", chain_yaml(300)), ("side300", side_effects_yaml(300))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--tmp", default="/tmp/rgraph_plan_fingerprints", help="folder for the generated graphs")
    args = parser.parse_args()
    folder = Path(args.tmp)
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in generated():
        path = folder / "g.yaml"
        path.write_text(text)
        spec = frontend(path, size=(16, 16)).spec
        for policy in POLICIES:
            if policy == "optimal" and "big" in name:
                continue  # seconds each: the search's full budget
            print(name, policy, digest(compile_plan(spec, policy=policy)), flush=True)
    for graph in sorted(Path("graphs").glob("*.yaml")):  # relative: the plan records the path
        spec = frontend(graph, size=(64, 64)).spec
        for policy in ("aliased", "optimal"):
            print(graph.name, policy, digest(compile_plan(spec, policy=policy)), flush=True)


if __name__ == "__main__":
    main()

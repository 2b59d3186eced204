"""Random graphs under validation with or without the layer workarounds: which report a message.

    python3 benchmarks/layer_workarounds.py --graphs 30 --off          # the layer setup installs
    VK_LAYER_PATH=/usr/share/vulkan/explicit_layer.d \\
        python3 benchmarks/layer_workarounds.py --graphs 30 --off      # Debian 12's 1.3.239

Each graph comes from ``rgraph.random_graph`` (1-29 passes, dedicated or aliased memory, drawn
from ``random.Random(--seed)``) and runs 2 frames at 16x16 under validation, synchronization
validation and the data check. Prints one line per graph that reports a message or wrong data,
then the count and the layer's version (docs/plan.md "Validation-layer 1.3.239 workarounds").
"""

from __future__ import annotations

import argparse
import random
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path.cwd()))  # the checkout it is run from, not an installed rgraph


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--graphs", type=int, default=30)
    parser.add_argument("--seed", type=int, default=21)
    parser.add_argument("--off", action="store_true", help="record without the layer workarounds")
    args = parser.parse_args()

    from rgraph.compiler.pipeline import compile_spec, frontend
    from rgraph.random_graph import random_graph, to_yaml
    from rgraph.vk.executor import execute_plan
    from rgraph.vk.instance import validation_layer_version

    rng = random.Random(args.seed)
    folder = Path(tempfile.mkdtemp(prefix="rgraph_workarounds_"))
    reported = 0
    for k in range(args.graphs):
        seed, passes, policy = rng.randrange(10**6), rng.randrange(1, 30), rng.choice(["dedicated", "aliased"])
        path = folder / f"g{k}.yaml"
        path.write_text(to_yaml(random_graph(seed, passes)))
        plan = compile_spec(frontend(path, size=(16, 16)).spec, policy=policy)
        result = execute_plan(plan, validate=True, frames=2, check_data=True,
                              **({"workarounds": ()} if args.off else {}))
        if result.messages or not result.data_ok:
            reported += 1
            ids = sorted({m.id_name for m in result.messages})
            print(f"random_graph({seed}, {passes}) {policy}: {len(result.messages)} message(s) {ids}, "
                  f"data {'ok' if result.data_ok else 'WRONG'}", flush=True)
    version = ".".join(map(str, validation_layer_version() or ()))
    print(f"{args.graphs} random graphs, workarounds {'off' if args.off else 'on'}, layer {version}: "
          f"{reported} reported")
    return 0


if __name__ == "__main__":
    sys.exit(main())

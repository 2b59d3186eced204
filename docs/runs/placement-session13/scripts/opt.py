import time, sys
from pathlib import Path
from rgraph.memory.instance import Instance
from rgraph.memory.trace import read_trace
from rgraph.memory.aliased import place_class
for path in sorted(Path("/work/shared/data/minimalloc").glob("*.csv")):
    inst = Instance.build(read_trace(path))
    t0 = time.process_time(); r = place_class(inst, 10.0, exact=True); t = time.process_time() - t0
    print(f"{path.stem[0]} optimal {r.peak/r.lower_bound:.3f}x proven={r.proven} {r.how:14s} CPU {t:6.2f} s", flush=True)

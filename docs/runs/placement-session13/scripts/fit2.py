"""Min CPU of whole improve runs (fresh Flat each run) vs own dive ops and dives*n."""
import sys, time, json
import numpy as np
from pathlib import Path
from rgraph.memory import elastic
from rgraph.memory.elastic import improve
from rgraph.memory.instance import Instance
from rgraph.memory.search import preorder
from rgraph.memory.trace import read_trace
from rgraph.memory.aliased import ELASTIC_ORDERS
from rgraph.memory.greedy import best_fit, orderings
REP = int(sys.argv[1])
elastic.DIVE_BLOCK_OPS = 0  # measure own ops only
rows = []
for path in sorted(Path("/work/shared/data/minimalloc").glob("*.csv")):
    inst = Instance.build(read_trace(path))
    inc = min(inst.peak(o) for o in (best_fit(inst, order) for _, order in orderings(inst)) if o is not None)
    orders = [preorder(inst, h) for h in ELASTIC_ORDERS]
    inst.neighbors, inst.section_blocks
    full = improve(inst, orders, inc, 1 << 40)
    for frac in (0.1, 0.3, 1.0):
        budget = int(full.ops * frac) if frac < 1 else 1 << 40
        best = 1e9
        for r in range(REP):
            inst.accelerated.clear()
            t0 = time.process_time(); f = improve(inst, orders, inc, budget); t = time.process_time() - t0
            best = min(best, t)
        rows.append((path.stem[0], inst.n, f.ops, f.dives, best))
        print(path.stem[0], inst.n, f.ops, f.dives, f"{1e3*best:.2f} ms", f"{f.ops/best/1e6:.1f} M/s", flush=True)
json.dump(rows, open("/tmp/h13/fit2.json", "w"))
ops = np.array([r[2] for r in rows], float); nd = np.array([r[1]*r[3] for r in rows], float); t = np.array([r[4] for r in rows])
A = np.stack([ops, nd], 1); W = 1 / t
c, *_ = np.linalg.lstsq(A * W[:, None], t * W, rcond=None)
print("rel fit: %.1f M ops/s, %.1f ns per block-dive (%.1f ops)" % (1/c[0]/1e6, c[1]*1e9, c[1]/c[0]))
for R, b in [(175e6, 12), (150e6, 12), (150e6, 16), (140e6, 16), (125e6, 16)]:
    r = t / ((ops + b * nd) / R)
    print(R/1e6, b, "t/charged max %.2f median %.2f min %.2f" % (r.max(), np.median(r), r.min()))

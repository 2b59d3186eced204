import sys, time
from pathlib import Path
from rgraph.memory.instance import Instance
from rgraph.memory.trace import read_trace
from rgraph.memory import aliased, elastic
budget = float(sys.argv[1]) if len(sys.argv) > 1 else 0.05
rec = []
orig = aliased.improve
def timed(*a, **k):
    t0 = time.process_time(); r = orig(*a, **k); rec.append((time.process_time() - t0, r.ops, r.dives)); return r
aliased.improve = timed
for path in sorted(Path("/work/shared/data/minimalloc").glob("*.csv")):
    blocks = read_trace(path)
    best = None
    for rep in range(3):
        rec.clear()
        inst = Instance.build(blocks)
        t0 = time.process_time(); r = aliased.place_class(inst, budget); tot = time.process_time() - t0
        t, ops, dives = rec[0] if rec else (0, 0, 0)
        if best is None or t < best[0]: best = (t, ops, dives, tot, r.peak / r.lower_bound, r.how)
    t, ops, dives, tot, ratio, how = best
    charged = ops / aliased.DIVE_OPS_PER_SECOND
    print(f"{path.stem[0]} ratio {ratio:.3f} {how:14s} dives {dives:3d} dive ops {ops:9d} charged {1e3*charged:6.1f} ms  improve CPU {1e3*t:6.1f} ms ({t/charged if charged else 0:.2f})  place_class CPU {1e3*tot:6.1f} ms")

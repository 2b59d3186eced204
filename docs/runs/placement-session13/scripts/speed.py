"""One full dive from the bound (TAW), Python vs compiled: min CPU of 5 (flat copy made beforehand)."""
import time
from pathlib import Path
from rgraph.memory.elastic import dive_python, native_dive, NATIVE
from rgraph.memory.instance import Instance
from rgraph.memory.search import preorder
from rgraph.memory.trace import read_trace
rs = []
for path in sorted(Path("/work/shared/data/minimalloc").glob("*.csv")):
    inst = Instance.build(read_trace(path)); o = preorder(inst, "TAW"); lb = inst.lower_bound()
    t0 = time.process_time(); native_dive(NATIVE, inst, o, lb); flat = time.process_time() - t0
    def best(f):
        m = 1e9
        for _ in range(5):
            t0 = time.process_time(); d = f(); m = min(m, time.process_time() - t0)
        return m, d
    tp, dp = best(lambda: dive_python(inst, o, lb)); tc, dc = best(lambda: native_dive(NATIVE, inst, o, lb))
    assert (dp.offsets, dp.blamed, dp.ops) == (dc.offsets, dc.blamed, dc.ops)
    rs.append(tp / tc)
    print(f"{path.stem[0]} ops {dp.ops:7d}  python {1e3*tp:6.2f} ms ({dp.ops/tp/1e6:4.1f} M/s)  compiled {1e3*tc:5.3f} ms ({dc.ops/tc/1e6:5.1f} M/s)  x{tp/tc:5.1f}  first call (flat copy) {1e3*flat:5.3f} ms")
print("speedup %.0f-%.0fx" % (min(rs), max(rs)))

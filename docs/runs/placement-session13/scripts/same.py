"""place_class at 50 ms with and without the compiled dive: same result; CPU of each."""
import time
from pathlib import Path
from rgraph.memory import elastic
from rgraph.memory.instance import Instance
from rgraph.memory.trace import read_trace
from rgraph.memory.aliased import place_class
native = elastic.NATIVE
for path in sorted(Path("/work/shared/data/minimalloc").glob("*.csv")):
    blocks = read_trace(path)
    out = []
    for mod in (native, None):
        elastic.NATIVE = mod
        t0 = time.process_time(); r = place_class(Instance.build(blocks), 0.05); t = time.process_time() - t0
        out.append((r.offsets, r.peak, r.how, r.proven, t))
    assert out[0][:4] == out[1][:4], path
    print(f"{path.stem[0]} identical {out[0][1]/r.lower_bound:.3f}x {out[0][2]:12s} CPU compiled {1e3*out[0][4]:6.1f} ms  python {1e3*out[1][4]:7.1f} ms")

"""The whole sync phase compiled (``rgraph/compiler/_sync_walk.pyx``: ``synchronize``) against
``rgraph.compiler.sync.synchronize``, the Python reference: the same barriers (and their order),
releases, waits, signals and start and end states, on a graph whose barrier groups make
rectangles of every shape (one cell, the whole image, runs of layers merged over mips, an L),
on queues that hand cells over, and on random graphs."""

from __future__ import annotations

from pathlib import Path

import pytest

from rgraph.compiler import phases, sync
from rgraph.compiler.pipeline import compilation, frontend
from rgraph.random_graph import random_graph, to_yaml

WHOLE = sync._WALK
pytestmark = pytest.mark.skipif(WHOLE is None or not hasattr(WHOLE, "synchronize"),
                                reason="compiled sync not built (setup.py build_ext)")

#: ``arr`` (3 mips x 4 layers): after ``z``, ``a`` and ``b`` its cells have three histories, so
#: the whole-image read in ``c`` (on the compute queue: releases on graphics) gets three groups:
#: a's 2 cells (mip 0, layers 0-1), b's square (mips 1-2, layers 1-2: merged over mips) and z's
#: L (mip 0 layers 2-3; mips 1-2 layers 0 and 3). ``d`` reads part of it back on graphics; the
#: persistent ``side`` ends with one cell in another state (a per-cell end state).
RECTANGLES = """\
rgraph: 1
name: rectangles
resources:
  arr: {kind: image, format: r32_sfloat, size: output, mips: 3, layers: 4}
  side: {kind: image, format: r32_sfloat, size: output, mips: 2, layers: 3, lifetime: persistent}
  out: {kind: buffer, bytes: 256}
  out2: {kind: buffer, bytes: 256}
passes:
  z: {kind: compute, writes: {arr: storage_write}}
  a: {kind: transfer, writes: {"arr[mip=0, layer=0:2]": transfer_dst, "side[mip=1, layer=1:3]": transfer_dst}}
  b: {kind: raster, writes: {"arr[mip=1:3, layer=1:3]": storage_write}}
  c: {kind: compute, queue: compute, reads: {arr: sampled, "side[mip=0:2, layer=0:2]": sampled},
      writes: {out: storage_write}}
  d: {kind: compute, reads: {"arr[mip=0:2, layer=0:4]": sampled, "side[mip=0:2, layer=0:2]": sampled},
      writes: {out2: storage_write}}
outputs: [out, out2]
"""


def both(c) -> tuple[object, object]:
    """The compiled phase's result, then the Python reference's, for compilation ``c``."""
    offsets, aliases = c.placement.offsets, c.aliases
    named = {n for preds in aliases.values() for n in preds}.union(aliases)
    ranges = {n: (heap, off, off + c.memory[n].bytes) for n in named for heap, off in (offsets[n],)}
    args = (c.passes, c.spec.resources, c.trace, aliases, ranges, set(c.spec.outputs))
    native = WHOLE.synchronize(*args)
    assert native is not None
    return native, sync.synchronize(*args)


def same(native, python) -> None:
    for field in ("barriers", "releases", "waits", "signals", "signal_values", "final", "initial"):
        assert getattr(native, field) == getattr(python, field), field


def test_rectangles_of_every_shape(tmp_path: Path) -> None:
    path = tmp_path / "g.yaml"
    path.write_text(RECTANGLES)
    c = compilation(frontend(path, size=(16, 16)).spec)
    native, python = both(c)
    same(native, python)
    index = {p.name: i for i, p in enumerate(c.passes)}
    got = [(b.subresource.mips, b.subresource.layers, b.src.layout, b.src.stages)
           for b in native.barriers[index["c"]] if b.resource == "arr"]
    # sorted by subresource; the square merged over mips 1-2, the L's layer-0 and layer-3 runs too
    assert got == [((0, 1), (0, 2), "TRANSFER_DST_OPTIMAL", ("COPY",)),
                   ((0, 1), (2, 4), "GENERAL", ("COMPUTE_SHADER",)),
                   ((1, 3), (0, 1), "GENERAL", ("COMPUTE_SHADER",)),
                   ((1, 3), (1, 3), "GENERAL", ("FRAGMENT_SHADER",)),
                   ((1, 3), (3, 4), "GENERAL", ("COMPUTE_SHADER",))]
    # z releases its L to c's queue: the acquire's rectangles, in rectangle order
    assert [(b.subresource.mips, b.subresource.layers) for b in native.releases[index["z"]]] == [
        ((0, 1), (2, 4)), ((1, 3), (0, 1)), ((1, 3), (3, 4))]
    assert [b.resource for b in native.releases[index["a"]]] == ["arr", "side"]  # by resource
    assert native.waits[index["c"]] and native.waits[index["d"]] and any(native.signals)
    assert isinstance(native.final["side"], tuple) and native.final["arr"] is None


@pytest.mark.parametrize("seed,passes", [(0, 60), (5, 200), (32, 10), (77, 400), (1000, 1000)])
def test_random_graphs_synchronize_alike(tmp_path: Path, seed: int, passes: int) -> None:
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=seed, passes=passes)))
    same(*both(compilation(frontend(path, size=(16, 16)).spec)))


def test_a_synchronize_started_during_one_declines(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A second compiled phase while one runs (another thread, or reentered through the Python
    it calls) returns None (the caller runs the twin, sync.py compiled as it is), so the tables
    the running one points into are never reset under it; the plan stays the same, also where
    the compiled phase always declines."""
    from rgraph.compiler.pipeline import compile_plan
    from rgraph.plan import dump

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=12, passes=80)))
    spec = frontend(path, size=(16, 16)).spec
    c = compilation(spec)
    expected = dump(c.plan)
    args = (c.passes, c.spec.resources, c.trace, c.aliases, None, set(spec.outputs))
    inner: list[object] = []
    handoffs = WHOLE.with_partial_handoffs

    def reentering(*a, **k):  # called by the compiled phase once, while it runs
        inner.append(WHOLE.synchronize(*args))
        return handoffs(*a, **k)

    monkeypatch.setattr(WHOLE, "with_partial_handoffs", reentering)
    assert dump(compile_plan(spec)) == expected
    assert inner == [None]
    monkeypatch.setattr(WHOLE, "synchronize", lambda *a: None)
    assert phases.SYNC_NATIVE is not None  # the twin
    assert dump(compile_plan(spec)) == expected


def depth_reads_yaml(count: int) -> str:
    """``count - 1`` passes each reading a depth image as depth_read and sampled at once: each
    pass's use of it is a merged scope, a new object for the compiled phase's scope table."""
    lines = ["rgraph: 1", f"name: depth_reads_{count}", "resources:", "  acc: {kind: buffer, bytes: 256}",
             "  d: {kind: image, format: d32_sfloat, size: output}", "passes:",
             "  p0: {kind: raster, writes: {acc: storage_write, d: depth_attachment}}"]
    lines += [f"  p{i}: {{kind: raster, reads: {{d: [depth_read, sampled]}}, writes: {{acc: storage_rw}}}}"
              for i in range(1, count)]
    return "\n".join(lines + ["outputs: [acc]"]) + "\n"


def test_a_full_scope_table_retries_from_empty_tables(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """1,500 merged scopes (the next phase then starts from empty tables), 800, then 1,500 again:
    that last phase starts with the table 800 full and fills it past half; it then runs once
    more from empty tables (not the twin) and gives the Python reference's result."""
    class NoTwin:
        @staticmethod
        def synchronize(*args):
            raise AssertionError("the compiled phase declined")

    calls: list[int] = []
    handoffs = WHOLE.with_partial_handoffs

    def counting(*args):  # called once per run of the compiled phase
        calls.append(1)
        return handoffs(*args)

    monkeypatch.setattr(phases, "SYNC_NATIVE", NoTwin)
    monkeypatch.setattr(WHOLE, "with_partial_handoffs", counting)
    for count, runs in ((1500, None), (800, 1), (1500, 2)):
        path = tmp_path / f"g{count}.yaml"
        path.write_text(depth_reads_yaml(count))
        c = compilation(frontend(path, size=(16, 16)).spec)
        assert runs is None or len(calls) == runs, count
        calls.clear()
        same(*both(c))
        calls.clear()


def test_barriers_are_reused_across_compiles(tmp_path: Path) -> None:
    """A compile of the same graph, from the same spec or a freshly parsed one, gets the
    earlier compile's barrier objects (equal values are one object) and each pass's tuple of
    them, still the reference's."""
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=5, passes=200)))
    first, python = both(compilation(frontend(path, size=(16, 16)).spec))
    same(first, python)
    for spec in (frontend(path, size=(16, 16)).spec, frontend(path, size=(16, 16)).spec):
        again, python = both(compilation(spec))
        same(again, python)
        for kind in ("barriers", "releases"):
            old, new = getattr(first, kind), getattr(again, kind)
            assert all(a is b for olds, news in zip(old, new, strict=True) for a, b in zip(olds, news, strict=True)), kind
        assert all(a is b for a, b in zip(first.barriers, again.barriers, strict=True))  # each pass's tuple too
    assert any(first.releases)


def test_more_barriers_than_the_table_lists(tmp_path: Path) -> None:
    """More distinct barriers than the table lists (4,096): the rest are made and kept for the
    one compile; the next compile starts from an empty table."""
    count = 2100  # buffers written by w, read by r (a barrier each), written again by x (another)
    names = [f"b{k}" for k in range(count)]
    lines = ["rgraph: 1", "name: many_barriers", "resources:"]
    lines += [f"  {n}: {{kind: buffer, bytes: 256}}" for n in names]
    lines += ["  out: {kind: buffer, bytes: 256}", "passes:"]
    for name, kind, usage, extra in (("w", "writes", "storage_write", ()), ("r", "reads", "storage_read", ()),
                                     ("x", "writes", "storage_write", ("out: storage_rw",))):
        lines += [f"  {name}:", "    kind: compute", f"    {kind}:"] + [f"      {n}: {usage}" for n in names]
        if name == "r":
            lines += ["    writes:", "      out: storage_write"]
        lines += [f"      {e}" for e in extra]
    lines += ["outputs:"] + [f"  - {n}" for n in names + ["out"]]
    path = tmp_path / "g.yaml"
    path.write_text("\n".join(lines) + "\n")
    native, python = both(compilation(frontend(path, size=(16, 16)).spec))
    assert len({id(b) for bs in native.barriers for b in bs}) > 4096
    same(native, python)
    small = tmp_path / "small.yaml"
    small.write_text(to_yaml(random_graph(seed=0, passes=60)))
    same(*both(compilation(frontend(small, size=(16, 16)).spec)))


def test_resources_of_other_classes_read_by_attribute(tmp_path: Path) -> None:
    """Traces and resource specs of subclasses (not read from their slots) give the same result."""
    import dataclasses

    from rgraph.compiler.trace import ResourceTrace
    from rgraph.spec.specialize import ResourceSpec

    class OtherTrace(ResourceTrace):
        pass

    class OtherSpec(ResourceSpec):
        pass

    def copy(value, cls):
        return cls(**{f.name: getattr(value, f.name) for f in dataclasses.fields(value)})

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=5, passes=200)))
    c = compilation(frontend(path, size=(16, 16)).spec)
    expected = both(c)[0]
    trace = dataclasses.replace(c.trace, resources={n: copy(r, OtherTrace) for n, r in c.trace.resources.items()})
    spec = dataclasses.replace(c.spec, resources={n: copy(r, OtherSpec) for n, r in c.spec.resources.items()})
    native, python = both(dataclasses.replace(c, trace=trace, spec=spec))
    same(native, python)
    same(native, expected)

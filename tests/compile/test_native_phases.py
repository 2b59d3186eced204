"""The compiled compiler phases (``rgraph/**/_*.pyx``: cull, trace, measure, place, emit, the
best fit and the elastic dive; sync.py compiled as it is, and the whole phase and its cell walk `_sync_walk.pyx`) against the pure-Python code they mirror: byte-identical plans
on random graphs under every policy, on graphs with optional reads, culled passes and
several queues, and on every bundled graph. A plan differing anywhere fails."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rgraph.compiler import emit, memory, phases, queue_order, sync, trace
from rgraph.compiler.pipeline import compile_plan, frontend
from rgraph.ir import cull
from rgraph.memory import elastic, greedy
from rgraph.memory import instance as instance_module
from rgraph.plan import dump
from rgraph.random_graph import random_graph, to_yaml

#: (module, attribute) of every compiled accelerator a compile can use.
SWITCHES = [(cull, "NATIVE"), (trace, "NATIVE"), (memory, "NATIVE"), (queue_order, "NATIVE"), (emit, "NATIVE"),
            (phases, "SYNC_NATIVE"), (sync, "_WALK"), (greedy, "NATIVE"), (instance_module, "_NATIVE"), (elastic, "NATIVE")]
BUILT = [getattr(module, name) is not None for module, name in SWITCHES]
GRAPHS = sorted((Path(__file__).resolve().parents[2] / "graphs").glob("*.yaml"))

pytestmark = pytest.mark.skipif(not all(BUILT), reason="compiled accelerators not built (setup.py build_ext)")


def rows(accesses) -> list[tuple]:
    """A trace's plan accesses per pass as tuples (the compiled walk's are, the Python walk's lists)."""
    return [tuple(row) for row in accesses]


def both(spec, monkeypatch: pytest.MonkeyPatch, **options) -> tuple[str, str]:
    """The plan's JSON compiled with the accelerators, then with the Python code only."""
    native = dump(compile_plan(spec, **options))
    with monkeypatch.context() as m:
        for module, name in SWITCHES:
            m.setattr(module, name, None)
        python = dump(compile_plan(spec, **options))
    return native, python


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(1, 120),
       policy=st.sampled_from(("aliased", "dedicated", "tlsf")))
def test_random_graphs_compile_alike(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed: int, passes: int,
                                     policy: str) -> None:
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    native, python = both(frontend(path, size=(16, 16)).spec, monkeypatch, policy=policy)
    assert native == python


@pytest.mark.parametrize("graph", GRAPHS, ids=[g.stem for g in GRAPHS])
def test_bundled_graphs_compile_alike(graph: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    native, python = both(frontend(graph, size=(64, 64)).spec, monkeypatch, policy="aliased")
    assert native == python


def test_a_large_graph_compiles_alike(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """1,000 passes: past the best fit's sweep threshold and the elastic dives' start."""
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=1000, passes=1000)))
    native, python = both(frontend(path, size=(16, 16)).spec, monkeypatch, policy="aliased")
    assert native == python


#: A persistent buffer read at the frame's start, written, then read in the same layout: the
#: second frame's first read is covered by the first frame's last barrier (the walk's end state
#: carries what that barrier made visible), so it gets none.
PERSISTENT_READS = """\
rgraph: 1
name: persistent_reads
resources:
  b: {kind: buffer, bytes: 256, lifetime: persistent}
  o0: {kind: buffer, bytes: 256}
  o2: {kind: buffer, bytes: 256}
passes:
  p0: {kind: compute, reads: {b: storage_read}, writes: {o0: storage_write}}
  p1: {kind: compute, writes: {b: storage_write}}
  p2: {kind: compute, reads: {b: storage_read}, writes: {o2: storage_write}}
outputs: [o0, o2]
"""


def test_a_persistent_resource_s_frame_boundary_compiles_alike(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "g.yaml"
    path.write_text(PERSISTENT_READS)
    plan = compile_plan(frontend(path, size=(16, 16)).spec)
    first = next(p for p in plan.passes if p.name == "p0")
    assert not [b for b in first.barriers if b.resource == "b"]  # covered by the previous frame's barrier
    native, python = both(frontend(path, size=(16, 16)).spec, monkeypatch)
    assert native == python


def test_the_compiled_trace_reads_any_access_type(tmp_path: Path) -> None:
    """The compiled walk reads an ``AccessSpec``'s fields from its slots, and any other access
    object (here a subclass) through its attributes: both give the Python walk's values."""
    from dataclasses import replace as dc_replace

    from rgraph.spec.specialize import AccessSpec

    class Access(AccessSpec):
        __slots__ = ()

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=7, passes=60)))
    spec = frontend(path, size=(16, 16)).spec
    passes = [dc_replace(p, accesses=tuple(Access(*(getattr(a, f) for f in (
        "resource", "usage", "write", "mips", "layers", "stages", "optional", "loc", "refit"))) for a in p.accesses))
        for p in spec.passes]
    assert type(passes[0].accesses[0]) is Access
    native = trace.NATIVE.walk(passes, spec.resources, trace._SCOPES, trace._scope)
    python = trace.walk_python(spec.passes, spec.resources)
    assert rows(native[0]) == rows(python[0]) and native[2] == python[2] and native[3] == python[3]
    assert {n: (r.usages, r.first, r.last, r.cells) for n, r in native[1].items()} == \
        {n: (r.usages, r.first, r.last, r.cells) for n, r in python[1].items()}


def test_compiles_in_threads_give_the_same_plan(tmp_path: Path) -> None:
    """The compiled cell walk keeps tables across calls: compiles in several threads at once
    (the GIL changes hands inside a walk, at its Python calls) give the one-thread plan."""
    import sys
    import threading

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=11, passes=400)))
    spec = frontend(path, size=(16, 16)).spec
    expected = dump(compile_plan(spec))
    results: list[str] = []
    errors: list[BaseException] = []

    def work() -> None:
        try:
            for _ in range(3):
                results.append(dump(compile_plan(spec)))
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # hand the GIL over as often as possible
    try:
        threads = [threading.Thread(target=work) for _ in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(interval)
    assert not errors, errors
    assert len(results) == 12 and all(r == expected for r in results)


def test_the_access_table_keys_on_pass_kind_and_format(tmp_path: Path) -> None:
    """The compiled trace walk finds each access's scope and subresource by the access object
    (``_trace.pyx``'s table), keyed also by its pass's kind and its resource's format code:
    the same access objects in passes of another kind, or on resources of another format,
    give the Python walk's scopes, not the ones remembered from the first walk."""
    from dataclasses import replace

    from rgraph import formats

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=7, passes=120)))
    spec = frontend(path, size=(16, 16)).spec
    passes, resources = list(spec.passes), dict(spec.resources)

    def walks_alike(ps, rs) -> None:
        native = trace.NATIVE.walk(ps, rs, trace._SCOPES, trace._scope)
        python = trace.walk_python(ps, rs)
        assert rows(native[0]) == rows(python[0])  # the plan accesses (stages, access, layout, subresource)
        assert [(n, r.cells) for n, r in native[1].items()] == [(n, r.cells) for n, r in python[1].items()]

    trace.NATIVE.reset_access_table()
    walks_alike(passes, resources)  # notes the passes
    walks_alike(passes, resources)  # lists them
    swapped = [replace(p, kind="raytrace") if p.kind == "compute" else p for p in passes]
    assert swapped != passes
    walks_alike(swapped, resources)
    depth = next(f for f in formats.all_formats() if f.has_depth and not f.has_stencil)
    recoded = {n: replace(r, format=depth) if r.kind == "image" and r.format is not None and not r.format.has_depth
               else r for n, r in resources.items()}
    walks_alike(passes, recoded)


def test_the_access_table_gives_a_listed_pass_s_values_and_uses_again(tmp_path: Path) -> None:
    """A pass's first walk notes it, its second lists it: then its plan values (its tuple of them)
    and its uses of its cells (but those merged from several accesses) are the objects of that
    walk where its index is the same; at another index (here: the first pass left out) it gets
    new uses; after ``reset_access_table`` all are new: every walk gives the Python walk's
    results."""
    from collections import Counter

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=9, passes=150)))
    spec = frontend(path, size=(16, 16)).spec
    passes, resources = list(spec.passes), spec.resources

    def walk(ps) -> tuple:
        native = trace.NATIVE.walk(ps, resources, trace._SCOPES, trace._scope)
        python = trace.walk_python(ps, resources)
        assert rows(native[0]) == rows(python[0]) and native[2] == python[2] and native[3] == python[3]
        assert [(n, r.usages, r.first, r.last, r.cells) for n, r in native[1].items()] == \
            [(n, r.usages, r.first, r.last, r.cells) for n, r in python[1].items()]
        return native

    def uses(walked) -> list:
        return [u for r in walked[1].values() for _, cell_uses in r.cells for u in cell_uses]

    merged = {(i, c) for i, p in enumerate(passes)
              for c, k in Counter(c for a in p.accesses for c in a.cells).items() if k > 1}

    trace.NATIVE.reset_access_table()
    noted = walk(passes)  # notes every pass
    first = walk(passes)  # lists them
    assert not any(a is b for a, b in zip(noted[0], first[0], strict=True))
    again = walk(passes)
    assert all(a is b for a, b in zip(first[0], again[0], strict=True))
    cells = [(u[0], c) for r in first[1].values() for c, cell_uses in r.cells for u in cell_uses]
    assert merged and [a is b for a, b in zip(uses(first), uses(again), strict=True)] == [k not in merged for k in cells]
    shifted = walk(passes[1:])
    assert all(a is b for a, b in zip(first[0][1:], shifted[0], strict=True))  # the values do not hold the index
    assert not {id(u) for u in uses(first)} & {id(u) for u in uses(shifted)}
    trace.NATIVE.reset_access_table()
    fresh = walk(passes)
    assert not any(a is b for a, b in zip(first[0], fresh[0], strict=True))


def test_the_scope_table_keys_on_the_objects_alike() -> None:
    """The compiled walk finds the scope of an access of no explicit stages by the pointers of its
    usage, kind and refit (``_trace.pyx``'s scope table): equal usage strings that are other
    objects, a refitted accel build after a plain one, and explicit stages give the Python
    walk's scopes."""
    from dataclasses import replace

    spec = frontend(Path(__file__).resolve().parents[2] / "graphs" / "rt_hybrid.yaml", size=(64, 64)).spec
    copied = [replace(p, accesses=tuple(replace(a, usage="".join(list(a.usage)),
                                                stages=("compute",) if p.kind == "compute" else None)
                                        for a in p.accesses)) for p in spec.passes]
    refitted = [replace(p, accesses=tuple(replace(a, refit=a.usage == "accel_build") for a in p.accesses))
                for p in spec.passes]
    assert any(a.stages for p in copied for a in p.accesses) and any(a.refit for p in refitted for a in p.accesses)
    for ps in (list(spec.passes), [*spec.passes, *copied, *refitted]):
        native = trace.NATIVE.walk(ps, spec.resources, trace._SCOPES, trace._scope)
        python = trace.walk_python(ps, spec.resources)
        assert rows(native[0]) == rows(python[0]) and native[2] == python[2]
        assert [(n, r.usages, r.cells) for n, r in native[1].items()] == \
            [(n, r.usages, r.cells) for n, r in python[1].items()]


def test_the_subresource_table_gives_plan_values_alike(tmp_path: Path) -> None:
    """The compiled walk finds an image access's subresource by its ranges as C longs
    (``_trace.pyx``'s subresource table), and through ``plan_values`` where they are not pairs of
    ints (here of an int subclass): both give the Python walk's values."""
    from dataclasses import replace

    class Int(int):
        pass

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=3, passes=80)))
    spec = frontend(path, size=(16, 16)).spec
    odd = [replace(p, accesses=tuple(a if a.mips is None else replace(a, mips=(Int(a.mips[0]), Int(a.mips[1])))
                                     for a in p.accesses)) for p in spec.passes]
    assert any(type(a.mips[0]) is Int for p in odd for a in p.accesses if a.mips is not None)
    for ps in (list(spec.passes), odd):
        native = trace.NATIVE.walk(ps, spec.resources, trace._SCOPES, trace._scope)
        python = trace.walk_python(ps, spec.resources)
        assert rows(native[0]) == rows(python[0])  # (subresources among the values)


def test_the_optional_scan_agrees(tmp_path: Path) -> None:
    """``cull._has_optional``'s compiled scan answers as the Python one, with and without an
    optional access (first, last or none)."""
    from dataclasses import replace

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=3, passes=60)))
    passes = [replace(p, accesses=tuple(replace(a, optional=False) for a in p.accesses))
              for p in frontend(path, size=(16, 16)).spec.passes]
    with_last = [*passes[:-1], replace(passes[-1], accesses=(*passes[-1].accesses[:-1],
                                                            replace(passes[-1].accesses[-1], optional=True)))]
    with_first = [replace(passes[0], accesses=(replace(passes[0].accesses[0], optional=True),
                                               *passes[0].accesses[1:])), *passes[1:]]
    for ps, expected in ((passes, False), (with_last, True), (with_first, True), ([], False)):
        assert cull.NATIVE.has_optional(ps) is expected
        assert cull._has_optional_python(ps) is expected


#: Mips and layers: cells of several-cell resources numbered in ``plain``'s tables.
CELLS_GRAPH = """rgraph: 1
name: cells
resources:
  out: {kind: image, format: r8g8b8a8_unorm, size: [16, 16], mips: 2, layers: 3}
  tmp: {kind: image, format: r8g8b8a8_unorm, size: [16, 16], mips: 3, layers: 2}
  hist: {kind: image, format: r8g8b8a8_unorm, size: [16, 16], mips: 2, lifetime: persistent}
  dead: {kind: buffer, bytes: 256}
  buf: {kind: buffer, bytes: 256}
passes:
  both_mips: {kind: compute, writes: {out: storage_write}}
  feed: {kind: compute, writes: {tmp: storage_write}}
  feed1: {kind: compute, writes: {"tmp[mip=1:3]": storage_write}}
  unused: {kind: compute, writes: {dead: storage_write}}
  mip0: {kind: compute, reads: {"tmp[mip=0:1]": storage_read}, writes: {"out[mip=0:1]": storage_write}}
  mip0_again: {kind: compute, reads: {"tmp[mip=2:3]": storage_read}, writes: {"out[mip=0:1]": storage_write}}
  layer: {kind: compute, writes: {"out[mip=1:2, layer=1:2]": storage_write, buf: storage_write}}
  rw: {kind: compute, reads: {buf: storage_read}, writes: {"hist[mip=1:2]": storage_rw}}
outputs: [out]
"""


def test_the_compiled_plain_cull_agrees(tmp_path: Path) -> None:
    """``cull._plain`` compiled (one walk over numbered cells, None at an optional access) gives
    the Python one's kept and culled passes: on random graphs, a graph of mips and layers, and
    None on graphs with an optional read (first or last)."""
    from dataclasses import replace

    from rgraph.ir.graph import READ_WRITE_USAGES

    specs = []
    for seed, passes in ((3, 60), (9, 150), (1000, 1000), (17, 5)):
        path = tmp_path / f"g{seed}.yaml"
        path.write_text(to_yaml(random_graph(seed=seed, passes=passes)))
        specs.append(frontend(path, size=(16, 16)).spec)
    path = tmp_path / "cells.yaml"
    path.write_text(CELLS_GRAPH)
    specs.append(frontend(path, size=(16, 16)).spec)
    for spec in specs:
        native = cull.NATIVE.plain(spec, spec.passes, READ_WRITE_USAGES, cull.Culled)
        assert native is not None
        assert native == cull._split(spec.passes, cull._alive_python(spec, spec.passes))
        first, last = spec.passes[0], spec.passes[-1]
        with_last = [*spec.passes[:-1], replace(last, accesses=(*last.accesses[:-1],
                                                               replace(last.accesses[-1], optional=True)))]
        with_first = [replace(first, accesses=(replace(first.accesses[0], optional=True), *first.accesses[1:])),
                      *spec.passes[1:]]
        for ps in (with_last, with_first):
            assert cull.NATIVE.plain(spec, ps, READ_WRITE_USAGES, cull.Culled) is None
    # ``mip0``'s write of ``out`` mip 0 is overwritten, so ``feed``'s ``tmp`` (its mip 0) is not
    # needed; ``feed1``'s mip 2 is (``mip0_again``); ``rw`` writes a persistent image and reads
    # ``buf`` from ``layer``
    assert [c.pass_name for c in cull.cull(specs[-1]).culled] == ["feed", "unused", "mip0"]


@pytest.mark.parametrize("seed,passes", [(1, 40), (9, 150), (1000, 1000)])
def test_the_compiled_walk_groups_reads_as_read_layouts(tmp_path: Path, seed: int, passes: int) -> None:
    """``walk(..., moved=[])`` finds ``read_layouts.to_general``'s reads during the walk (no read
    groups kept): the same reads as ``to_general`` of the Python walk's groups; and, among those
    graphs' groups, some of several reads in one layout (they stay) and some mixed (they move)."""
    from rgraph.compiler.read_layouts import GENERAL_READS, to_general

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=seed, passes=passes)))
    spec = frontend(path, size=(16, 16)).spec
    moved: list[tuple[int, int]] = []
    native = trace.NATIVE.walk(spec.passes, spec.resources, trace._SCOPES, trace._scope, moved)
    python = trace.walk_python(spec.passes, spec.resources)
    groups = {n: r.group for n, r in python[1].items() if r.group is not None}
    assert moved == to_general(groups)
    assert all(r.group is None for r in native[1].values())
    assert rows(native[0]) == rows(python[0]) and native[2] == python[2] and native[3] == python[3]
    if passes == 1000:
        alike = 0  # groups of several movable reads in one layout (a walk that moved any group would fail)
        for seq in groups.values():
            run: list[str | None] = []
            for _, _, write, usage, layout in [*seq, (-1, -1, True, "", None)]:
                if not write:
                    if usage in GENERAL_READS:
                        run.append(layout)
                    continue
                alike += len(run) > 1 and len(set(run)) == 1
                run = []
        assert moved and alike


@pytest.mark.parametrize("seed,passes", [(9, 150), (1000, 1000)])
def test_the_compiled_trace_patches_moved_reads_alike(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed: int,
                                                      passes: int) -> None:
    """``trace.trace`` with the compiled walk and patch (``_trace.patch``: the reads moved to
    GENERAL, their plan accesses and their passes' merged uses) gives the Python trace."""
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=seed, passes=passes)))
    spec = frontend(path, size=(16, 16)).spec
    native = trace.trace(spec.passes, spec.resources)
    with monkeypatch.context() as m:
        m.setattr(trace, "NATIVE", None)
        python = trace.trace(spec.passes, spec.resources)
    assert rows(native.accesses) == rows(python.accesses) and native.waits == python.waits
    assert all(type(row) is tuple for row in native.accesses)  # the plan keeps them
    assert any(a.layout == "GENERAL" and a.usage == "sampled" for row in native.accesses for a in row)
    assert [(n, r.usages, r.first, r.last, r.cells) for n, r in native.resources.items()] == \
        [(n, r.usages, r.first, r.last, r.cells) for n, r in python.resources.items()]

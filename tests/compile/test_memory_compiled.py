"""The compiled measure and place helpers (``rgraph/compiler/_memory.pyx``) against the Python
code: the blocks ``place_resources`` builds, and the requirements read from the profile
provider's memos by the keys its ``image`` and ``buffer`` use."""

from __future__ import annotations

from pathlib import Path

import pytest

from rgraph.compiler import memory
from rgraph.compiler.pipeline import _default_provider, compilation, frontend
from rgraph.memory.model import Block
from rgraph.memory_requirements import ProfileMemoryRequirements
from rgraph.random_graph import random_graph, to_yaml

pytestmark = pytest.mark.skipif(memory.NATIVE is None, reason="compiled accelerators not built")


def test_blocks_equal_the_python_ones() -> None:
    mem = {
        "a": memory.ResourceMemory(1000, 256, 7, "device_local_optimal", ("sampled",), 0, 3),
        "b": memory.ResourceMemory(1024, 256, 7, "device_local_optimal", ("sampled",), 2, 5),
        "c": memory.ResourceMemory(5, 1, 7, "device_local_linear", (), 1, 1),
        "z": memory.ResourceMemory(64, 0, 7, "device_local_linear", (), 1, 1),  # check_blocks' error, not here
    }
    names = ["a", "b", "c", "z"]
    native = memory.NATIVE.blocks(names, mem)
    python = [Block(n, m.first, m.last, m.bytes, m.alignment, m.memory_class) for n in names for m in (mem[n],)]
    assert native == python and [type(b) for b in native] == [Block] * 4
    assert [b.aligned_size for b in native[:3]] == [1024, 1024, 5] == [b.aligned_size for b in python[:3]]
    assert "aligned_size" not in vars(native[3])  # computed on use, as before: ZeroDivisionError then
    with pytest.raises(ZeroDivisionError):
        _ = native[3].aligned_size
    start, end, size, alignment, classes = memory.NATIVE.columns(names, mem)  # the same, as columns
    assert list(zip(names, start, end, size, alignment, classes, strict=True)) == [
        (b.name, b.start, b.end, b.size, b.alignment, b.memory_class) for b in python]


def test_requirements_read_the_provider_memos_by_its_keys(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Once ``image`` and ``buffer`` filled their memos, the compiled requirements make no call:
    a key of its own (one field left out or in another form) would miss and call them."""
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=4, passes=120)))
    spec = frontend(path, size=(16, 16)).spec
    c = compilation(spec)
    provider = ProfileMemoryRequirements(_default_provider().profile, "copy")
    used = {name: r.usages for name, r in c.trace.resources.items()}
    python = memory.requirements_python(spec.resources, used, spec.outputs, provider)  # fills the memos
    assert provider.__dict__["_image_memo"] and provider.__dict__["_buffer_memo"]

    def no_call(*args, **kwargs):
        raise AssertionError("called")

    monkeypatch.setattr(provider, "image", no_call)
    monkeypatch.setattr(provider, "buffer", no_call)
    native = memory.NATIVE.requirements(spec.resources, used, spec.outputs, provider, memory._SAME_BUFFER_FLAG)
    assert native == python and list(native) == list(python)


@pytest.mark.parametrize("seed", range(6))
def test_place_resources_compiled_loops_match_python(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """``place_resources`` with the compiled ``split`` and ``dedicated`` against the Python
    loops: the same offsets, heaps and stats, on random resources (transients, outputs,
    persistent ones, names out of order, and none left to alias at all on seed 0)."""
    import random
    from types import SimpleNamespace

    rng = random.Random(seed)
    names = [f"r{k}" for k in rng.sample(range(100), 40)]
    lifetimes = ["persistent"] if seed == 0 else ["transient", "transient", "persistent", "output", "imported"]
    resources = {n: SimpleNamespace(lifetime=rng.choice(lifetimes)) for n in names}
    mem = {}
    for n in names:
        first = rng.randrange(20)
        mem[n] = memory.ResourceMemory(rng.randrange(1, 1 << 20), rng.choice([1, 256, 65536]), 7,
                                       rng.choice(["device_local_optimal", "device_local_linear"]), (),
                                       first, first + rng.randrange(5))
    outputs = rng.sample(names, 5)
    aliasable, rest = memory.NATIVE.split(resources, mem, outputs)
    assert aliasable == [n for n in sorted(mem) if resources[n].lifetime == "transient" and n not in outputs]
    assert rest == sorted(set(mem) - set(aliasable))
    transients = [n for n in mem if resources[n].lifetime == "transient"]
    for order in (mem, dict(sorted(mem.items()))):  # names out of order, then in name order
        want = [n for n in order if resources[n].lifetime == "transient"]
        assert memory.NATIVE.split_transients(resources, order, outputs) == (want, aliasable, rest)
    assert sorted(transients) == sorted(set(aliasable) | (set(transients) & set(outputs)))
    native = memory.place_resources(resources, mem, "aliased", outputs)
    monkeypatch.setattr(memory, "NATIVE", None)
    python = memory.place_resources(resources, mem, "aliased", outputs)
    assert native.offsets == python.offsets and list(native.offsets) == list(python.offsets)
    assert native.heaps == python.heaps
    assert native.stats.peak_bytes == python.stats.peak_bytes
    assert native.stats.allocations == python.stats.allocations
    assert native.stats.lower_bound_bytes == python.stats.lower_bound_bytes


@pytest.mark.parametrize("seed", [1, 7, 23, 99])
def test_compiled_measure_matches_python(tmp_path: Path, seed: int) -> None:
    """``_memory.measure`` (the whole measure phase compiled) against ``phases._measure_python``:
    the same values in the same key order, on random graphs with culled passes and outputs."""
    from rgraph.compiler import phases

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=seed, passes=150)))
    spec = frontend(path, size=(16, 16)).spec
    c = compilation(spec)
    python = phases._measure_python(c)
    native = memory.NATIVE.measure(spec.resources, c.trace.resources, spec.outputs, c.provider, c.culling.culled,
                                   spec.passes, spec.empty, memory._SAME_BUFFER_FLAG)
    for got, want in zip(native, python, strict=True):
        assert got == want and list(got) == list(want)
    assert [type(m) for m in native[0].values()] == [memory.ResourceMemory] * len(native[0])


def test_compiled_culled_only_finds_names_by_value_too(tmp_path: Path) -> None:
    """The compiled ``culled_only`` finds passes and traced resources by the address of their
    names; equal names in other string objects, and passes of another type, are found by value."""
    from types import SimpleNamespace

    from rgraph.compiler import phases
    from rgraph.ir.cull import Culled

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=5, passes=150)))
    spec = frontend(path, size=(16, 16)).spec
    c = compilation(spec)
    culled, traced = c.culling.culled, c.trace.resources
    want = phases._culled_only_python(spec, culled, traced)
    assert want[0], "the graph should have culled-only resources"
    copied = [Culled("".join(list(x.pass_name)), x.reason) for x in culled]  # equal, not the same object
    assert all(a.pass_name is not b.pass_name for a, b in zip(copied, culled, strict=True))
    retraced = {"".join(list(name)): r for name, r in traced.items()}
    for args in [(spec.passes, culled, traced), (spec.passes, copied, traced), (spec.passes, culled, retraced),
                 ([SimpleNamespace(name=p.name, accesses=p.accesses) for p in spec.passes], culled, traced)]:
        got = memory.NATIVE.culled_only(*args)
        assert got[0] == want[0] and list(got[0]) == list(want[0])
        assert [p.name for p in got[1]] == [p.name for p in want[1]]


@pytest.mark.parametrize("seed", [3, 11, 1000])
def test_compiled_cross_queue_conflicts_match_python(tmp_path: Path, seed: int) -> None:
    """``_queue_order.cross_queue_conflicts`` against the Python code: the same pairs, the
    same keys in the same order, each set filled in the same order."""
    from rgraph.compiler import queue_order

    if queue_order.NATIVE is None:
        pytest.skip("compiled accelerators not built")
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=seed, passes=400)))
    spec = frontend(path, size=(16, 16)).spec
    c = compilation(spec)
    candidates = [n for n in c.memory if spec.resources[n].lifetime == "transient"]
    for names in (candidates, candidates[::-1]):
        want = queue_order.cross_queue_conflicts_python(c.passes, c.trace, names)
        got = queue_order.NATIVE.cross_queue_conflicts(c.passes, c.trace, names)
        assert want, "the graph should have cross-queue pairs"
        assert got == want and list(got) == list(want)
        assert all(list(got[k]) == list(want[k]) for k in want)
    one_queue = [p for p in c.passes if p.queue == c.passes[0].queue]
    assert queue_order.NATIVE.cross_queue_conflicts(one_queue, c.trace, candidates) == {}


@pytest.mark.parametrize("seed", [2, 1000])
def test_compiled_alias_sources_match_python(tmp_path: Path, seed: int) -> None:
    """``_memory.alias_sources`` against ``alias_sources_python``: the same sources in the
    same order, with a heap's names in name order (as placements list them) and shuffled."""
    import random

    from rgraph.memory.model import Placement

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=seed, passes=400)))
    c = compilation(frontend(path, size=(16, 16)).spec)
    placement = c.placement
    items = list(placement.offsets.items())
    random.Random(seed).shuffle(items)
    for offsets in (placement.offsets, dict(items)):
        p = Placement(offsets, placement.heaps, placement.stats)
        want = memory.alias_sources_python(p, c.memory)
        got = memory.NATIVE.alias_sources(p, c.memory)
        assert want, "the graph should alias"
        assert got == want and list(got) == list(want)


def test_measure_reads_resources_of_another_type_by_attribute(tmp_path: Path) -> None:
    """``_memory.measure`` reads a ``ResourceSpec``'s slots directly and any other object's
    attributes: the same values either way."""
    from dataclasses import fields
    from types import SimpleNamespace

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed=7, passes=120)))
    spec = frontend(path, size=(16, 16)).spec
    c = compilation(spec)
    args = (c.trace.resources, spec.outputs, c.provider, c.culling.culled, spec.passes, spec.empty,
            memory._SAME_BUFFER_FLAG)
    plain = {n: SimpleNamespace(**{f.name: getattr(r, f.name) for f in fields(r)}) for n, r in spec.resources.items()}
    want = memory.NATIVE.measure(spec.resources, *args)
    got = memory.NATIVE.measure(plain, *args)
    assert got == want and list(got[0]) == list(want[0]) == list(c.memory)

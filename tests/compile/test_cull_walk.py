"""Culling's backwards walk (``rgraph.ir.cull._alive``) keeps exactly the passes the
edge-based definition keeps: RAW ancestors of the last writers of kept resources and of
side-effect passes (``raw_ancestors(dependencies(...), _roots(...))``)."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rgraph.compiler.pipeline import frontend
from rgraph.ir.cull import _alive, _drop_unproduced_reads, _roots
from rgraph.ir.graph import dependencies, raw_ancestors
from rgraph.random_graph import random_graph, to_yaml


def both(spec) -> tuple[set[str], set[str]]:
    kept, _, _ = _drop_unproduced_reads(spec, dict(spec.removed))
    return _alive(spec, kept), raw_ancestors(dependencies(kept), _roots(spec, kept))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(2, 60))
def test_walk_equals_edges_on_random_graphs(tmp_path: Path, seed: int, passes: int) -> None:
    path = tmp_path / f"g_{seed}_{passes}.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    walk, edges = both(frontend(path, size=(16, 16)).spec)
    assert walk == edges


PARTIAL = """rgraph: 1
name: partial
resources:
  out: {kind: image, format: r8g8b8a8_unorm, size: [16, 16], mips: 2}
  tmp: {kind: image, format: r8g8b8a8_unorm, size: [16, 16], mips: 2}
  dead: {kind: buffer, bytes: 256}
passes:
  both_mips: {kind: compute, writes: {out: storage_write}}
  feed: {kind: compute, writes: {tmp: storage_write}}
  unused: {kind: compute, writes: {dead: storage_write}}
  mip0: {kind: compute, reads: {"tmp[mip=0:1]": storage_read}, writes: {"out[mip=0:1]": storage_write}}
  mip0_again: {kind: compute, writes: {"out[mip=0:1]": storage_write}}
outputs: [out]
"""


def test_walk_keeps_the_last_writer_of_each_cell(tmp_path: Path) -> None:
    """``both_mips`` still writes mip 1 last; ``mip0`` is overwritten by ``mip0_again`` and
    so reaches no output, and neither does ``feed``, its producer, nor ``unused``."""
    path = tmp_path / "partial.yaml"
    path.write_text(PARTIAL)
    walk, edges = both(frontend(path, size=(16, 16)).spec)
    assert walk == edges == {"both_mips", "mip0_again"}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(2, 60))
def test_forward_walk_without_removals_equals_the_general_walk(tmp_path: Path, seed: int, passes: int) -> None:
    """With no pass removed by the scene, ``_drop_unproduced_reads`` takes a one-loop path
    (``_drop_optional_reads``); the general walk, made to run by a removal of no pass, agrees."""
    path = tmp_path / f"g_{seed}_{passes}.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    spec = frontend(path, size=(16, 16)).spec
    if spec.removed:
        return
    assert _drop_unproduced_reads(spec, {}) == _drop_unproduced_reads(spec, {"<no such pass>": "test"})


def test_forward_walk_drops_an_optional_read_nothing_writes() -> None:
    """forward_noao.yaml: nothing writes ``ao``; both walks drop the optional read alike."""
    from locations import TESTS

    spec = frontend(TESTS / "pass_graphs" / "forward_noao.yaml", size=(32, 32)).spec
    assert not spec.removed
    fast = _drop_unproduced_reads(spec, {})
    assert [(d.pass_name, d.resource) for d in fast[1]] == [("forward", "ao")]
    assert fast == _drop_unproduced_reads(spec, {"<no such pass>": "test"})

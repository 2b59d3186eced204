"""PlanCache: a hit returns the same plan without compiling; any input change recompiles."""

from __future__ import annotations

import time
from pathlib import Path

from rgraph.compiler.cache import PlanCache
from rgraph.plan import dump

GRAPH = """rgraph: 1
name: cached
params: {n: 256}
resources:
  a: {kind: buffer, bytes: "${params.n}"}
  b: {kind: buffer, bytes: 256}
passes:
  p0: {kind: compute, writes: {a: storage_write}}
  p1: {kind: compute, reads: {a: storage_read}, writes: {b: storage_write}}
outputs: [b]
"""


def test_hits_misses_and_invalidation(tmp_path: Path) -> None:
    path = tmp_path / "g.yaml"
    path.write_text(GRAPH)
    cache = PlanCache()
    first = cache.plan(path, size=(16, 16))
    assert (cache.hits, cache.misses) == (0, 1)
    start = time.perf_counter()
    again = cache.plan(path, size=(16, 16))
    hit_s = time.perf_counter() - start
    assert again is first and (cache.hits, cache.misses) == (1, 1)
    assert hit_s < 0.05  # a stat and a dict lookup; the benchmark figure is in docs/performance.md
    changed = cache.plan(path, params={"n": "512"}, size=(16, 16))
    assert changed is not first and cache.misses == 2
    assert [r.bytes for r in changed.resources if r.name == "a"] == [512]
    assert cache.plan(path, size=(16, 16), policy="dedicated") is not first
    path.write_text(GRAPH.replace("b: {kind: buffer, bytes: 256}", "b: {kind: buffer, bytes: 1024}"))
    edited = cache.plan(path, size=(16, 16))
    assert edited is not first and [r.bytes for r in edited.resources if r.name == "b"] == [1024]
    path.write_text(GRAPH)  # same bytes again, new mtime: compiles once, then hits
    restored = cache.plan(path, size=(16, 16))
    assert dump(restored) == dump(first)
    assert cache.plan(path, size=(16, 16)) is restored


def test_capacity_evicts_the_least_recent(tmp_path: Path) -> None:
    path = tmp_path / "g.yaml"
    path.write_text(GRAPH)
    cache = PlanCache(capacity=2)
    a = cache.plan(path, params={"n": "1"}, size=(16, 16))
    cache.plan(path, params={"n": "2"}, size=(16, 16))
    cache.plan(path, params={"n": "3"}, size=(16, 16))
    assert cache.plan(path, params={"n": "1"}, size=(16, 16)) is not a


VALUES = """rgraph: 1
name: values
params: {n: 256, gain: 1.5}
resources:
  a: {kind: buffer, bytes: "${params.n}"}
  b: {kind: buffer, bytes: 256}
passes:
  p0: {kind: compute, writes: {a: storage_write}, params: {gain: "${params.gain}"}}
  p1: {kind: compute, reads: {a: storage_read}, writes: {b: storage_write}}
outputs: [b]
"""


def test_a_value_only_param_reuses_the_compiled_structure(tmp_path: Path) -> None:
    """``gain`` reaches only pass params: the plan is reused with the new values, and equals
    a fresh compile byte for byte; ``n`` sizes a buffer: that recompiles."""
    from rgraph.compiler.pipeline import compile_graph_plan

    path = tmp_path / "values.yaml"
    path.write_text(VALUES)
    cache = PlanCache()
    first = cache.plan(path, size=(16, 16))
    louder = cache.plan(path, params={"gain": "3.0"}, size=(16, 16))
    assert (cache.misses, cache.reused) == (2, 1)
    assert dump(louder) == dump(compile_graph_plan(path, params={"gain": "3.0"}, size=(16, 16)))
    assert dump(louder) != dump(first)
    bigger = cache.plan(path, params={"n": "512"}, size=(16, 16))
    assert cache.reused == 1 and [r.bytes for r in bigger.resources if r.name == "a"] == [512]
    assert dump(cache.plan(path, params={"gain": "1.5"}, size=(16, 16))) == dump(first)  # back: reused
    assert cache.reused == 2
    cache.plan(path, params={"gain": "3.0"}, size=(16, 16), policy="dedicated")  # other options: compiles
    assert cache.reused == 2


def test_surgery_param_change_equals_a_fresh_compile() -> None:
    from rgraph.compiler.pipeline import compile_graph_plan

    cache = PlanCache()
    cache.plan("surgery", size=(64, 64))
    changed = cache.plan("surgery", params={"hbao.strength": "2.5"}, size=(64, 64))
    assert cache.reused == 1
    assert dump(changed) == dump(compile_graph_plan("surgery", params={"hbao.strength": "2.5"}, size=(64, 64)))


def test_a_feature_that_culls_a_pass_recompiles() -> None:
    from rgraph.compiler.pipeline import compile_graph_plan
    from rgraph.resources import resolve_scene

    cache = PlanCache()
    cache.plan("surgery", scene_path=resolve_scene("cct"), size=(64, 64))
    no_decals = cache.plan("surgery", scene_path=resolve_scene("cct_no_decals"), size=(64, 64))
    assert cache.reused == 0 and "decals" in {c.pass_name for c in no_decals.culled}
    fresh = compile_graph_plan("surgery", scene_path=resolve_scene("cct_no_decals"), size=(64, 64))
    assert dump(no_decals) == dump(fresh)

"""Aliasing keeps async overlap: under ``aliased`` no pass waits for another queue where
``dedicated`` does not, nor for a later point of it (random multi-queue graphs)."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rgraph.check import check_plan
from rgraph.compiler.pipeline import compile_spec, frontend
from rgraph.random_graph import random_graph, to_yaml


def waits(plan: dict) -> list[set[tuple[str, str]]]:
    """Per pass: the (queue, signalling pass) it waits for (values depend on how many
    passes signal, so waits are compared by the pass that signals)."""
    by_value = {(s["queue"], s["value"]): p["name"] for p in plan["passes"] for s in p["signals"]}
    return [{(w["queue"], by_value[(w["queue"], w["value"])]) for w in p["waits"]} for p in plan["passes"]]


def multi_queue_spec(tmp: Path, seed: int, passes: int):
    path = tmp / f"g_{seed}_{passes}.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    return frontend(path, size=(16, 16)).spec


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(4, 40))
def test_aliased_waits_are_a_subset_of_dedicated(tmp_path: Path, seed: int, passes: int) -> None:
    spec = multi_queue_spec(tmp_path, seed, passes)
    aliased = compile_spec(spec, policy="aliased")
    dedicated = compile_spec(spec, policy="dedicated")
    for i, (a, d) in enumerate(zip(waits(aliased), waits(dedicated), strict=True)):
        assert a <= d, f"pass {i} ({aliased['passes'][i]['name']}): aliased waits {sorted(a - d)} beyond {sorted(d)}"
    assert not check_plan(aliased)


CHAIN = """
rgraph: 1
name: per_consumer_signals
resources:
  a: {kind: image, format: r32_sfloat, size: [16, 16]}
  a2: {kind: image, format: r32_sfloat, size: [16, 16]}
  b: {kind: image, format: r32_sfloat, size: [16, 16]}
  c: {kind: image, format: r32_sfloat, size: [16, 16]}
  g: {kind: image, format: r32_sfloat, size: [16, 16]}
  out: {kind: image, format: r32_sfloat, size: [16, 16]}
passes:
  c1: {kind: compute, queue: compute, writes: {a: storage_write, a2: storage_write}}
  c2: {kind: compute, queue: compute, reads: {a: sampled}, writes: {b: storage_write}}
  c3: {kind: compute, queue: compute, reads: {b: sampled}, writes: {c: storage_write}}
  g1: {kind: compute, reads: {a2: sampled}, writes: {g: storage_write}}
  g2: {kind: compute, reads: {g: sampled, c: sampled}, writes: {out: storage_write}}
outputs: [out]
"""


def test_a_consumer_waits_for_the_pass_it_needs_and_that_pass_signals(tmp_path: Path) -> None:
    """g1 needs only c1's a2: it waits for c1's own signal, not the end of the compute
    chain, and the runtime ends a batch after every signalling pass. (Had c2 also read a2,
    g1 would wait for c2: the compute queue releases ownership after its last use.)"""
    from rgraph.vk.lower.batches import make_batches

    path = tmp_path / "chain.yaml"
    path.write_text(CHAIN)
    spec = frontend(path, size=(16, 16)).spec
    for policy in ("aliased", "dedicated"):
        plan = compile_spec(spec, policy=policy)
        by_name = {p["name"]: i for i, p in enumerate(plan["passes"])}
        assert waits(plan)[by_name["g1"]] == {("compute", "c1")}
        assert waits(plan)[by_name["g2"]] == {("compute", "c3")}
        assert [p["name"] for p in plan["passes"] if p["signals"]] == ["c1", "c3"]

        class OneQueuePerName:
            @staticmethod
            def same_queue(a: str, b: str) -> bool:
                return a == b

        batches = make_batches(plan, OneQueuePerName())  # type: ignore[arg-type]
        compute = [[p["name"] for p in b.passes] for b in batches if b.queue == "compute"]
        assert compute == [["c1"], ["c2", "c3"]]

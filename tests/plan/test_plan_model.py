"""The typed plan: load/dump round trips byte-identically; malformed plans give one located line."""

from __future__ import annotations

import copy
import json
import re

import pytest
from locations import TESTS

from rgraph import plan as rplan
from rgraph.errors import RGraphError
from rgraph.plan.model import Barrier, Plan, State

GOLDEN = sorted((TESTS / "golden").glob("*.json"))
HAND_WRITTEN = sorted((TESTS / "plans").glob("*.json")) + [TESTS / "report_plans" / "forward.json"]
SURGERY = TESTS / "golden" / "surgery_cct.json"


@pytest.mark.parametrize("path", GOLDEN, ids=lambda p: p.stem)
def test_golden_plans_round_trip_byte_identical(path):
    text = path.read_text()
    plan = rplan.load(path)
    assert isinstance(plan, Plan)
    assert rplan.dump(plan) == text
    assert rplan.load(text) == plan  # text works as well as a path
    assert rplan.to_json_dict(plan) == json.loads(text)


@pytest.mark.parametrize("path", HAND_WRITTEN, ids=lambda p: p.stem)
def test_hand_written_plans_round_trip_to_their_canonical_text(path):
    """Hand-formatted files come back as their canonical text (same document, sorted keys)."""
    doc = json.loads(path.read_text())
    assert rplan.dump(rplan.load(path)) == rplan.dumps_json(doc)


def test_model_is_typed_and_frozen():
    plan = rplan.load(SURGERY)
    b = next(b for p in plan.passes for b in p.barriers if b.aliases)
    assert isinstance(b, Barrier) and isinstance(b.src, State) and isinstance(b.aliases, tuple)
    no_alias = next(b for p in plan.passes for b in p.barriers if not b.aliases)
    assert no_alias.aliases == ()
    with pytest.raises(AttributeError):
        b.resource = "x"  # type: ignore[misc]
    r = plan.resource(b.resource)
    assert r.name == b.resource and r.is_image
    buffers = [r for r in plan.resources if not r.is_image]
    assert buffers and all(r.buffer_bytes == (r.size_bytes or r.bytes) for r in buffers)
    assert plan.stats.barriers == plan.barrier_count
    assert plan.format == rplan.PLAN_FORMAT


def test_aliases_json_keeps_name_list_or_null():
    assert rplan.aliases_json(()) is None
    assert rplan.aliases_json(("a",)) == "a"
    assert rplan.aliases_json(("a", "b")) == ["a", "b"]


def _doc():
    return json.loads(SURGERY.read_text())


def _first(doc, key):
    return next(i for i, p in enumerate(doc["passes"]) if p[key])


def _error(doc) -> str:
    text = json.dumps(doc, indent=1, sort_keys=True)
    with pytest.raises(RGraphError) as info:
        rplan.parse(text, "plan.json")
    message = str(info.value)
    assert "\n" not in message
    return message


B = _first(_doc(), "barriers")
W = _first(_doc(), "waits")
P, A = next((i, j) for i, p in enumerate(_doc()["passes"]) for j, a in enumerate(p["accesses"]) if a["subresource"])

CASES = [
    # deleted keys
    (lambda d: d.pop("passes"), r"top level: missing key 'passes'"),
    (lambda d: d["passes"][B].pop("barriers"), rf"passes\[{B}\]: missing key 'barriers'"),
    (lambda d: d["passes"][B]["barriers"][0]["src"].pop("layout"), rf"passes\[{B}\]\.barriers\[0\]\.src: missing key 'layout'"),
    (lambda d: d["resources"][0].pop("bytes"), r"resources\[0\]: missing key 'bytes'"),
    # wrong types and values
    (lambda d: d["passes"][B]["barriers"][0]["src"].update(layout=7),
     rf"passes\[{B}\]\.barriers\[0\]\.src\.layout: expected an upper-case Vulkan name"),
    (lambda d: d["passes"][B]["barriers"][0]["src"].update(stages="COMPUTE_SHADER"),
     rf"passes\[{B}\]\.barriers\[0\]\.src\.stages: expected a list, got \"COMPUTE_SHADER\""),
    (lambda d: d["passes"][0].update(queue="video"), r"passes\[0\]\.queue: expected one of graphics, compute, transfer"),
    (lambda d: d["resources"][0].update(offset=1.5), r"resources\[0\]\.offset: expected an integer"),
    (lambda d: d["resources"][0].update(bytes=2**70), r"resources\[0\]\.bytes: expected an integer in \[0, "),
    (lambda d: d["resources"][0].update(bytes=-1), r"resources\[0\]\.bytes: expected an integer in"),
    (lambda d: d["passes"][0]["accesses"][0].update(write="yes"), r"passes\[0\]\.accesses\[0\]\.write: expected true or false"),
    (lambda d: d["passes"][P]["accesses"][A]["subresource"].update(layers=[3, 1]),
     rf"passes\[{P}\]\.accesses\[{A}\]\.subresource\.layers: expected a half-open range"),
    (lambda d: d.update(format="rgraph-plan/2"), r"format: expected 'rgraph-plan/1'"),
    (lambda d: d["passes"][0].update(colour="red"), r"passes\[0\]\.colour: unknown key 'colour'"),
    (lambda d: d["passes"][0].update(params={"a": [[[[[[1]]]]]]}), r"passes\[0\]\.params\.a.*expected a number"),
    (lambda d: d["stats"].update(barriers=True), r"stats\.barriers: expected an integer"),
    # bad references and inconsistencies
    (lambda d: d["passes"][B]["barriers"][0].update(resource="nope"),
     rf"passes\[{B}\]\.barriers\[0\]\.resource: no resource 'nope' in resources"),
    (lambda d: d["passes"][0]["accesses"][0].update(resource="nope"),
     r"passes\[0\]\.accesses\[0\]\.resource: no resource 'nope'"),
    (lambda d: d["passes"][1].update(index=7), r"passes\[1\]\.index: expected 1 \(the pass's position\), got 7"),
    (lambda d: d["passes"][W]["waits"][0].update(queue="transfer"), rf"passes\[{W}\]\.waits\[0\]\.queue: queue 'transfer' is not in"),
    (lambda d: d["resources"][0].update(heap=99), r"resources\[0\]\.heap: no heap with id 99"),
    (lambda d: d["resources"][0].update(offset=d["heaps"][d["resources"][0]["heap"]]["bytes"]),
     r"resources\[0\]\.offset: offset \d+ \+ bytes \d+ exceeds heap"),
    (lambda d: d["resources"][0].update(last=1000), r"resources\[0\]\.last: pass index 1000 out of range"),
    (lambda d: d["outputs"].append("ghost"), r"outputs\[\d+\]: no resource 'ghost'"),
    (lambda d: d["passes"][P]["accesses"][A]["subresource"].update(mips=[0, 9]),
     rf"passes\[{P}\]\.accesses\[{A}\]\.subresource\.mips: range \[0, 9\] exceeds"),
    (lambda d: d["resources"].append(copy.deepcopy(d["resources"][0])), r"resources\[\d+\]: duplicate resource"),
    (lambda d: d["passes"][0].update(kind="magic"), r"passes\[0\]\.kind: unknown pass kind 'magic'"),
    (lambda d: d["passes"][P]["accesses"][A].update(usage="sampledd"),
     rf"passes\[{P}\]\.accesses\[{A}\]\.usage: unknown usage 'sampledd'"),
    (lambda d: d["resources"][0]["usages"].append("bogus"), r"resources\[0\]\.usages\[\d+\]: unknown usage 'bogus'"),
    (lambda d: next(r for r in d["resources"] if r["kind"] == "image").update(format="R8G8B8A8_FANCY"),
     r"resources\[\d+\]\.format: unknown format 'R8G8B8A8_FANCY'"),
]


@pytest.mark.parametrize(("mutate", "message"), CASES)
def test_malformed_plans_give_one_located_line(mutate, message):
    doc = _doc()
    mutate(doc)
    assert re.match(rf"plan\.json:\d+:\d+: error: malformed plan: {message}", _error(doc)), _error(doc)


def test_location_is_the_offending_value():
    doc = _doc()
    doc["passes"][B]["barriers"][0]["src"]["layout"] = 7
    text = json.dumps(doc, indent=1, sort_keys=True)
    with pytest.raises(RGraphError) as info:
        rplan.parse(text, "plan.json")
    d = info.value.first.location
    assert text.splitlines()[d.line - 1][d.col - 1:].startswith("7")


@pytest.mark.parametrize(("text", "message"), [
    ("{\n \"format\": [,]\n}", r"plan\.json:2:13: error: invalid JSON: Expecting value"),
    ("[" * 100000 + "]" * 100000, r"plan\.json:1:1: error: invalid JSON: nested too deeply"),
    ('{"format": ' + "9" * 5000 + "}", r"plan\.json:1:1: error: invalid JSON: Exceeds the limit"),
    ("[1, 2]", r"plan\.json:1:1: error: malformed plan: top level: expected an object"),
])
def test_undecodable_text(text, message):
    with pytest.raises(RGraphError) as info:
        rplan.parse(text, "plan.json")
    assert re.match(message, str(info.value)), str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(RGraphError) as info:
        rplan.load(tmp_path / "nope.json")
    assert str(info.value) == f"{tmp_path / 'nope.json'}:1:1: error: plan file not found"


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("policy", ("dedicated", "aliased", "tlsf"))
def test_compiled_and_naive_plans_load_and_round_trip(tmp_path, seed, policy):
    """No false rejections: what the compiler writes (also --sync naive) loads back equal."""
    from rgraph.compiler.naive_sync import naive_sync
    from rgraph.compiler.pipeline import compile_plan, frontend
    from rgraph.random_graph import random_graph, to_yaml

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed, 10 + 7 * seed)))
    plan = compile_plan(frontend(path, size=(16, 16)).spec, policy=policy)
    for p in (plan, naive_sync(plan)):
        text = rplan.dump(p)
        assert rplan.load(text) == p
        assert rplan.dump(rplan.load(text)) == text


@pytest.mark.parametrize("graph, options", [
    (TESTS / "data" / "rt" / "rt_probe.yaml", {}),  # a build pass with the compiler's accel_scratch access
    ("rt_hybrid", {"scene_path": TESTS.parent / "graphs" / "scenes" / "rt_living_room.yaml", "camera": 1}),
], ids=["rt_probe", "rt_hybrid_camera"])
def test_ray_tracing_plans_round_trip(graph, options):
    """Accel layouts, scratch buffers, trace_indirect and --camera survive the typed model."""
    from rgraph.compiler.pipeline import compile_graph_plan

    plan = compile_graph_plan(graph, size=(32, 32), **options)
    text = rplan.dump(plan)
    again = rplan.load(text)
    assert again == plan and rplan.dump(again) == text
    doc = json.loads(text)
    accels = [r for r in doc["resources"] if r["kind"] == "accel"]
    assert accels and all("blas" in r["accel"] and "tlas" in r["accel"] for r in accels)
    assert doc.get("camera", 0) == options.get("camera", 0)

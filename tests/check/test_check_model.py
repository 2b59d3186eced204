"""The checker's happens-before model on tiny plans, and its building blocks."""

from __future__ import annotations

import json

import pytest
from locations import TESTS
from plans.check_builder import access, barrier, gpass, plan_of, resource, scope

from rgraph.check import RAW, SEMAPHORE, WAR, WAW, check_plan
from rgraph.check.aliasing import analyse
from rgraph.check.cells import CellMap, merge_rects
from rgraph.check.chains import ChainRegistry
from rgraph.check.plan import read_plan
from rgraph.check.vocab import ALL_STAGES, STAGE_BIT, access_mask, stage_mask
from rgraph.jsonloc import locate

BUF = None  # buffers have no layout


def buffer_raw(write, src, dst, read) -> set[str]:
    """Pass 0 writes buffer x, pass 1 reads it behind one barrier: which hazards?"""
    plan = plan_of([
        gpass(0, "w", [access("x", write[0], write[1], write=True)]),
        gpass(1, "r", [access("x", read[0], read[1])], [barrier("x", scope(*src, BUF), scope(*dst, BUF))]),
    ], [resource("x", "buffer", 0, 1)])
    return {h.kind for h in check_plan(plan)}


CS, FS, VS = ["COMPUTE_SHADER"], ["FRAGMENT_SHADER"], ["VERTEX_SHADER"]
STORE_W, SAMPLED = ["SHADER_STORAGE_WRITE"], ["SHADER_SAMPLED_READ"]


@pytest.mark.parametrize(("write", "src", "dst", "read", "expected"), [
    ((CS, STORE_W), (CS, STORE_W), (FS, SAMPLED), (FS, SAMPLED), set()),
    ((CS, STORE_W), (["ALL_COMMANDS"], ["MEMORY_WRITE"]), (["ALL_COMMANDS"], ["MEMORY_READ"]), (FS, SAMPLED), set()),
    ((CS, STORE_W), (["BOTTOM_OF_PIPE"], STORE_W), (FS, SAMPLED), (FS, SAMPLED), set()),
    ((CS, STORE_W), (["TOP_OF_PIPE"], STORE_W), (FS, SAMPLED), (FS, SAMPLED), {RAW}),
    ((CS, STORE_W), ([], STORE_W), (FS, SAMPLED), (FS, SAMPLED), {RAW}),
    ((CS, STORE_W), (CS, STORE_W), (["TOP_OF_PIPE"], ["SHADER_READ"]), (FS, SAMPLED), set()),
    ((CS, STORE_W), (CS, STORE_W), (["ALL_GRAPHICS"], ["SHADER_READ"]), (FS, ["SHADER_STORAGE_READ"]), set()),
    ((CS, STORE_W), (CS, STORE_W), (["ALL_GRAPHICS"], ["SHADER_READ"]), (CS, SAMPLED), {RAW}),
    ((CS, STORE_W), (CS, STORE_W), (["PRE_RASTERIZATION_SHADERS"], ["UNIFORM_READ"]), (VS, ["UNIFORM_READ"]), set()),
    ((CS, STORE_W), (CS, STORE_W), (["VERTEX_INPUT"], ["INDEX_READ"]), (["INDEX_INPUT"], ["INDEX_READ"]), set()),
    ((CS, STORE_W), (CS, STORE_W), (["VERTEX_INPUT"], ["INDEX_READ"]),
     (["INDEX_INPUT"], ["VERTEX_ATTRIBUTE_READ"]), {RAW}),
    ((CS, STORE_W), (CS, ["SHADER_WRITE"]), (FS, SAMPLED), (FS, SAMPLED), set()),
    ((CS, STORE_W), (CS, ["TRANSFER_WRITE"]), (FS, SAMPLED), (FS, SAMPLED), {RAW}),
    ((CS, STORE_W), (CS, STORE_W), (FS, ["UNIFORM_READ"]), (FS, SAMPLED), {RAW}),
    ((["ALL_TRANSFER"], ["TRANSFER_WRITE"]), (["COPY", "BLIT", "RESOLVE", "CLEAR", "ACCELERATION_STRUCTURE_COPY_KHR"],
                                               ["TRANSFER_WRITE"]), (CS, ["MEMORY_READ"]), (CS, SAMPLED), set()),
    ((["ALL_TRANSFER"], ["TRANSFER_WRITE"]), (["COPY"], ["TRANSFER_WRITE"]), (CS, ["MEMORY_READ"]), (CS, SAMPLED),
     {RAW}),  # a copy-only source scope misses the blit/clear/resolve stages of the write
    ((CS, STORE_W), (CS, STORE_W), (FS + VS, SAMPLED), (FS + VS, SAMPLED), set()),
    ((CS, STORE_W), (CS, STORE_W), (FS, SAMPLED), (FS + VS, SAMPLED), {RAW}),
])
def test_stage_and_access_scopes(write, src, dst, read, expected):
    assert buffer_raw(write, src, dst, read) == expected


def test_waw_follows_syncval_the_second_write_must_be_in_the_destination_access_scope():
    def waw(dst_access):
        plan = plan_of([
            gpass(0, "a", [access("x", CS, STORE_W, write=True)]),
            gpass(1, "b", [access("x", CS, STORE_W, write=True)],
                  [barrier("x", scope(CS, STORE_W, BUF), scope(CS, dst_access, BUF))]),
        ], [resource("x", "buffer", 0, 1)])
        return {h.kind for h in check_plan(plan)}

    assert waw(STORE_W) == set()
    assert waw(["SHADER_WRITE"]) == set()
    assert waw([]) == {WAW}


def test_execution_dependencies_are_global_a_barrier_on_another_resource_orders_a_war():
    def plan(with_y_barrier: bool):
        y_barrier = [barrier("y", scope(FS, [], BUF), scope(CS, [], BUF))] if with_y_barrier else []
        return plan_of([
            gpass(0, "read_x", [access("x", FS, ["UNIFORM_READ"]), access("y", FS, ["UNIFORM_READ"])],
                  [barrier(r, scope(CS, STORE_W, BUF), scope(FS, ["UNIFORM_READ"], BUF)) for r in ("x", "y")]),
            gpass(1, "write_x", [access("x", CS, STORE_W, write=True)], y_barrier),
        ], [resource("x", "buffer", 0, 1, lifetime="imported", initial=scope(CS, STORE_W, BUF)),
            resource("y", "buffer", 0, 1, lifetime="imported", initial=scope(CS, STORE_W, BUF))])

    assert check_plan(plan(True)) == []
    assert {h.kind for h in check_plan(plan(False))} == {WAR}


def test_barriers_of_one_batch_do_not_chain_but_consecutive_batches_do():
    def plan(y_barrier_pass):
        passes = [
            gpass(0, "read_x", [access("x", FS, ["UNIFORM_READ"])]),
            gpass(1, "idle", [access("y", VS, ["UNIFORM_READ"])]),
            gpass(2, "write_x", [access("x", CS, STORE_W, write=True)],
                  [barrier("x", scope(VS, [], BUF), scope(CS, [], BUF))]),
        ]
        passes[y_barrier_pass]["barriers"].append(barrier("y", scope(FS, [], BUF), scope(VS, [], BUF)))
        return plan_of(passes, [
            resource("x", "buffer", 0, 2, lifetime="imported", initial=scope(FS, ["UNIFORM_READ"], BUF)),
            resource("y", "buffer", 0, 2, lifetime="imported", initial=scope(FS + VS, ["UNIFORM_READ"], BUF))])

    assert check_plan(plan(1)) == []  # FS -> VS (pass 1), then VS -> CS (pass 2): a chain
    assert {h.kind for h in check_plan(plan(2))} == {WAR}  # same batch: no chain


def test_chained_visibility_after_availability():
    """Make available with no visibility, chain through another barrier, then make visible."""
    plan = plan_of([
        gpass(0, "w", [access("x", CS, STORE_W, write=True)]),
        gpass(1, "avail", [access("y", FS, SAMPLED)], [barrier("x", scope(CS, STORE_W, BUF), scope(FS, [], BUF))]),
        gpass(2, "r", [access("x", VS, ["UNIFORM_READ"])], [barrier("x", scope(FS, [], BUF), scope(VS, ["UNIFORM_READ"], BUF))]),
    ], [resource("x", "buffer", 0, 2),
        resource("y", "buffer", 1, 1, lifetime="imported", initial=scope(CS, STORE_W, BUF))])
    plan["passes"][1]["barriers"].append(barrier("y", scope(CS, STORE_W, BUF), scope(FS, SAMPLED, BUF)))
    assert check_plan(plan) == []
    plan["passes"][1]["barriers"][0]["src"]["access"] = []  # never made available: the chain carries nothing
    assert {h.kind for h in check_plan(plan)} == {RAW}


def two_queue_plan(round_trip: bool):
    g, c = "graphics", "compute"
    passes = [
        gpass(0, "w", [access("x", CS, STORE_W, write=True)], signals=[{"queue": g, "value": 1, "stages": CS}]),
        gpass(1, "other", [access("y", CS, STORE_W, write=True)], queue=c,
              waits=[{"queue": g, "value": 1, "stages": CS}], signals=[{"queue": c, "value": 1, "stages": CS}]),
        gpass(2, "r", [access("x", FS, SAMPLED)], waits=[{"queue": c, "value": 1, "stages": FS}] if round_trip else []),
    ]
    return plan_of(passes, [resource("x", "buffer", 0, 2), resource("y", "buffer", 1, 1)], queues=[g, c])


def test_a_semaphore_round_trip_orders_a_queues_own_past():
    assert check_plan(two_queue_plan(True)) == []
    assert {h.kind for h in check_plan(two_queue_plan(False))} == {RAW}


def test_wait_before_signal_in_plan_order_is_scheduled_not_deadlocked():
    g, c = "graphics", "compute"
    plan = plan_of([
        gpass(0, "consumer", [access("x", CS, SAMPLED)], queue=g, waits=[{"queue": c, "value": 1, "stages": CS}]),
        gpass(1, "producer", [access("x", CS, STORE_W, write=True)], queue=c,
              signals=[{"queue": c, "value": 1, "stages": CS}]),
    ], [resource("x", "buffer", 0, 1)], queues=[g, c])
    hazards = check_plan(plan)
    assert SEMAPHORE not in {h.kind for h in hazards}
    plan["passes"][1]["signals"][0]["value"] = 0
    assert SEMAPHORE in {h.kind for h in check_plan(plan)}


def test_large_layer_count_is_handled_by_ranges():
    layers = 2048
    per_layer = [
        gpass(i, f"w{i}", [access("arr", CS, STORE_W, "GENERAL", True, {"mips": [0, 1], "layers": [i, i + 1]})])
        for i in range(layers)
    ]
    per_layer[0]["barriers"] = [barrier("arr", scope([], [], "UNDEFINED"), scope(CS, STORE_W, "GENERAL"),
                                        {"mips": [0, 1], "layers": [0, layers]})]
    read = gpass(layers, "read_all", [access("arr", FS, SAMPLED, "SHADER_READ_ONLY_OPTIMAL", False,
                                             {"mips": [0, 1], "layers": [0, layers]})],
                 [barrier("arr", scope(CS, STORE_W, "GENERAL"), scope(FS, SAMPLED, "SHADER_READ_ONLY_OPTIMAL"),
                          {"mips": [0, 1], "layers": [0, layers]})])
    plan = plan_of(per_layer + [read], [resource("arr", "image", 0, layers, layers=layers)])
    assert check_plan(plan) == []
    read["barriers"][0]["subresource"]["layers"] = [0, layers - 1]
    (raw, layout) = sorted(check_plan(plan), key=lambda h: h.kind)
    assert layout.kind == "layout mismatch"
    assert raw.kind == RAW and raw.subresource == ((0, 1), (layers - 1, layers))
    assert f"write by pass {layers - 1} 'w{layers - 1}'" in raw.message


# --- building blocks ---------------------------------------------------------------------


def test_cell_map_splits_and_merges():
    cells = CellMap((0, 3, 0, 8), "a")
    cells.update((1, 2, 2, 5), lambda s: s + "b")
    assert sorted(cells.query(None)) == sorted([
        ((0, 1, 0, 8), "a"), ((1, 2, 0, 2), "a"), ((1, 2, 2, 5), "ab"), ((1, 2, 5, 8), "a"), ((2, 3, 0, 8), "a")])
    assert list(cells.query((1, 2, 4, 6))) == [((1, 2, 4, 5), "ab"), ((1, 2, 5, 6), "a")]
    state = object()
    cells.update(None, lambda s: state)
    assert cells.interval_count() == 3  # one interval per mip again


def test_cell_map_changes_each_distinct_state_once():
    cells = CellMap((0, 1, 0, 4), 0)
    for layer in range(4):
        cells.update((0, 1, layer, layer + 1), lambda s, layer=layer: layer + 10)
    calls = []
    cells.update((0, 1, 1, 3), lambda s: calls.append(s) or -1)
    assert sorted(calls) == [11, 12]
    assert list(cells.query(None)) == [((0, 1, 0, 1), 10), ((0, 1, 1, 3), -1), ((0, 1, 3, 4), 13)]


def test_merge_rects():
    assert merge_rects([(0, 1, 0, 2), (0, 1, 2, 4), (1, 2, 0, 4)]) == [(0, 2, 0, 4)]


def test_chain_classes_merge_when_equal():
    reg = ChainRegistry()
    fs, cs, vs = STAGE_BIT["FRAGMENT_SHADER"], STAGE_BIT["COMPUTE_SHADER"], STAGE_BIT["VERTEX_SHADER"]
    a, b = reg.get(fs, 0), reg.get(vs, 0)
    reg.apply_batch([(fs | vs, cs)])
    assert reg.reach(a) == cs and reg.reach(b) == cs and len(reg) == 2  # (fs|cs, cs) and (vs|cs, cs)
    reg.apply_batch([(cs, fs | vs)])
    assert reg.find(a) == reg.find(b) and len(reg) == 1


def test_scope_expansion():
    assert stage_mask(["TOP_OF_PIPE"], "first") == 0 and stage_mask(["TOP_OF_PIPE"], "second") == ALL_STAGES
    assert stage_mask(["BOTTOM_OF_PIPE"], "first") == ALL_STAGES and stage_mask(["BOTTOM_OF_PIPE"], "second") == 0
    assert stage_mask(["ALL_TRANSFER"], "access") == stage_mask(["TRANSFER"], "access")
    assert stage_mask(["ALL_TRANSFER"], "access") & STAGE_BIT["COPY"]
    assert access_mask(["SHADER_READ"]) & access_mask(["SHADER_SAMPLED_READ"])
    assert not access_mask(["SHADER_READ"]) & access_mask(["UNIFORM_READ"])


def test_locate_finds_nested_values():
    text = json.dumps({"a": 1, "passes": [{"x": [1, 2]}, {"name": "b", "x": [3, {"deep": "here"}]}]}, indent=2)
    line, col = locate(text, ["passes", 1, "x", 1, "deep"])
    assert text.splitlines()[line - 1][col - 1:].startswith('"here"')
    assert locate(text, ["passes", 7]) == locate(text, ["passes"])


def test_aliasing_analysis_picks_direct_predecessors_only():
    def res(name, first, last, offset, nbytes):
        return resource(name, "buffer", first, last, heap=0, offset=offset, nbytes=nbytes)

    passes = [gpass(i, f"p{i}", [access(name, CS, STORE_W, write=True)])
              for i, name in enumerate(["old", "mid", "late"])]
    plan = read_plan(plan_of(passes, [res("old", 0, 0, 0, 100), res("mid", 1, 1, 0, 50), res("late", 2, 2, 0, 100)]))
    info = analyse(plan)
    names = {plan.resources[k].name: [plan.resources[e].name for e in v] for k, v in info.handoffs.items()}
    assert names == {"mid": ["old"], "late": ["mid", "old"]}  # 'old' still owns bytes 50..100
    assert info.overlaps == [] and info.lifetime_errors == []


def test_previous_frames_reads_keep_their_write_visible_only_to_them():
    def plan(read_stages):
        img = scope(CS, [], "GENERAL")
        return plan_of([gpass(0, "r", [access("x", read_stages, ["SHADER_STORAGE_READ"], "GENERAL")])],
                       [resource("x", lifetime="persistent", initial=img, final=img)])

    assert check_plan(plan(CS)) == []
    hazards = [h for h in check_plan(plan(FS)) if h.pass_name == "r"]
    assert [h.kind for h in hazards] == [RAW] and "the previous frame's last write" in hazards[0].message


def test_aliases_may_list_several_previous_occupants():
    plan = json.loads((TESTS / "plans" / "aliasing.json").read_text())
    plan["passes"][4]["barriers"][0]["aliases"] = ["a", "b", "c"]
    assert check_plan(plan) == []


def test_per_subresource_end_states():
    layer = [{"mips": [0, 1], "layers": [i, i + 1]} for i in range(2)]
    states = [dict(scope(FS, [], "SHADER_READ_ONLY_OPTIMAL"), subresource=layer[0]),
              dict(scope(CS, STORE_W, "GENERAL"), subresource=layer[1])]
    plan = plan_of([
        gpass(0, "use", [access("x", FS, SAMPLED, "SHADER_READ_ONLY_OPTIMAL", sub=layer[0]),
                         access("x", CS, STORE_W, "GENERAL", True, sub=layer[1])],
              [barrier("x", scope(CS, STORE_W, "GENERAL"), scope(CS, STORE_W, "GENERAL"), layer[1])]),
    ], [resource("x", layers=2, lifetime="persistent", initial=states, final=states)])
    assert check_plan(plan) == []
    plan["resources"][0]["final"] = [states[1] | {"subresource": layer[0]}, states[1]]
    hazards = check_plan(plan)
    assert {(h.kind, h.subresource) for h in hazards} == {("final state", ((0, 1), (0, 1))),
                                                           ("final state", ((0, 1), (0, 2)))}
    assert any("ends in SHADER_READ_ONLY_OPTIMAL but 'final' declares GENERAL" in h.message for h in hazards)

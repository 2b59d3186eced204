"""The hand-written fixture plans are clean; each targeted mutation reports the right hazard."""

from __future__ import annotations

import copy

import pytest
from plans.check_builder import (
    FIXTURES,
    barrier_on,
    every_single_drop,
    kinds,
    load,
    pass_named,
    resource_named,
    without,
)

from rgraph.check import (
    ALIASING_HANDOFF,
    ALIASING_OVERLAP,
    FINAL_STATE,
    LAYOUT_MISMATCH,
    LIFETIME,
    QUEUE_OWNERSHIP,
    RAW,
    SEMAPHORE,
    UNDEFINED_CONTENTS,
    WAR,
    WAW,
    Hazard,
    check_plan,
)


@pytest.mark.parametrize("name", FIXTURES)
def test_fixture_is_clean(name):
    assert check_plan(load(name)) == []


@pytest.mark.parametrize("name", FIXTURES)
def test_dropping_any_single_barrier_wait_or_signal_is_detected(name):
    plan = load(name)
    drops = list(every_single_drop(plan))
    assert drops, "fixture has no synchronization to drop"
    missed = [label for label, mutated in drops if not check_plan(mutated)]
    assert missed == []


# --- basic.json: one queue ------------------------------------------------------------------


def test_raw_missing_barrier_on_buffer():
    hazards = check_plan(without(load("basic"), "gbuffer", "params"))
    raw = [h for h in hazards if h.kind == RAW]
    assert {(h.pass_name, h.resource) for h in raw} == {("gbuffer", "params"), ("lighting", "params")}
    assert raw[0].subresource is None


def test_raw_message_names_pass_resource_range_and_missing_scope():
    plan = load("basic")
    barrier_on(plan, "lighting", "albedo")["dst"]["stages"] = ["COMPUTE_SHADER"]
    (h,) = check_plan(plan)
    assert h == Hazard(
        kind=RAW, pass_index=3, pass_name="lighting", resource="albedo", subresource=((0, 1), (0, 1)),
        message="pass 3 'lighting' reads 'albedo'[mips 0:1, layers 0:1] (FRAGMENT_SHADER/SHADER_SAMPLED_READ): "
                "RAW hazard: not visible after layout transition COLOR_ATTACHMENT_OPTIMAL -> "
                "SHADER_READ_ONLY_OPTIMAL by barrier 0 of pass 3 'lighting' [missing for FRAGMENT_SHADER]",
    )


def test_raw_when_source_access_scope_misses_the_write():
    plan = load("basic")
    barrier_on(plan, "gbuffer", "params")["src"]["access"] = []  # execution only: write never made available
    assert RAW in kinds(plan)


def test_raw_names_the_writer_when_visibility_is_to_the_wrong_access():
    plan = load("basic")
    barrier_on(plan, "gbuffer", "params")["dst"]["access"] = ["SHADER_STORAGE_READ"]
    hazards = check_plan(plan)
    assert {h.kind for h in hazards} == {RAW}
    assert all("write by pass 1 'patch' (ALL_TRANSFER/TRANSFER_WRITE)" in h.message for h in hazards)


def test_waw_missing_barrier():
    hazards = check_plan(without(load("basic"), "patch", "params"))
    assert [(h.kind, h.pass_name) for h in hazards] == [(WAW, "patch")]
    assert "write by pass 0 'cull' (COMPUTE_SHADER/SHADER_STORAGE_WRITE)" in hazards[0].message


def test_waw_needs_the_new_write_in_the_destination_access_scope():
    plan = load("basic")
    barrier_on(plan, "patch", "params")["dst"]["access"] = []  # execution + availability, no visibility
    assert kinds(plan) == {WAW}


def test_war_missing_barrier():
    hazards = check_plan(without(load("basic"), "update_params", "params"))
    assert {h.kind for h in hazards} == {WAR}
    assert {h.message.split("read by ")[1].split(" (")[0] for h in hazards} == {"pass 2 'gbuffer'", "pass 3 'lighting'"}


def test_war_barrier_must_cover_all_reads_since_the_write():
    plan = load("basic")
    barrier_on(plan, "update_params", "params")["src"]["stages"] = ["FRAGMENT_SHADER"]  # misses gbuffer's VERTEX read
    (h,) = check_plan(plan)
    assert h.kind == WAR and "read by pass 2 'gbuffer' (VERTEX_SHADER/UNIFORM_READ)" in h.message


def test_all_reads_between_writes_share_one_barrier():
    plan = load("basic")
    reads = [p["name"] for p in plan["passes"] for a in p["accesses"] if a["resource"] == "params" and not a["write"]]
    assert reads == ["gbuffer", "lighting"]
    assert "params" not in {b["resource"] for b in pass_named(plan, "lighting")["barriers"]}
    assert check_plan(plan) == []


def test_layout_mismatch_when_barrier_source_layout_is_wrong():
    plan = load("basic")
    barrier_on(plan, "lighting", "depth")["src"]["layout"] = "GENERAL"
    hazards = check_plan(plan)
    assert {h.kind for h in hazards} == {LAYOUT_MISMATCH}
    assert "expects GENERAL but the cells are in DEPTH_ATTACHMENT_OPTIMAL" in hazards[0].message


def test_missing_undefined_transition_is_a_layout_mismatch():
    hazards = check_plan(without(load("basic"), "gbuffer", "albedo"))
    first = hazards[0]
    assert (first.kind, first.pass_name, first.resource) == (LAYOUT_MISMATCH, "gbuffer", "albedo")
    assert "in UNDEFINED (no transition from UNDEFINED)" in first.message


def test_depth_read_and_sampled_share_depth_read_only_layout():
    plan = load("basic")
    depth = [a for a in pass_named(plan, "lighting")["accesses"] if a["resource"] == "depth"]
    assert {a["usage"] for a in depth} == {"depth_read", "sampled"}
    assert {a["layout"] for a in depth} == {"DEPTH_READ_ONLY_OPTIMAL"}
    assert check_plan(plan) == []
    barrier_on(plan, "lighting", "depth")["dst"]["stages"].remove("FRAGMENT_SHADER")
    assert kinds(plan) == {RAW}  # the sampled read now misses visibility


def test_read_after_read_in_the_same_layout_needs_no_barrier():
    plan = load("basic")
    assert "depth" not in {b["resource"] for b in pass_named(plan, "post")["barriers"]}
    assert check_plan(plan) == []


def test_discarding_contents_that_a_later_read_expects():
    plan = load("basic")
    barrier_on(plan, "lighting", "albedo")["src"]["layout"] = "UNDEFINED"
    hazards = check_plan(plan)
    assert {h.kind for h in hazards} == {UNDEFINED_CONTENTS}
    assert "discarded by the layout transition UNDEFINED -> SHADER_READ_ONLY_OPTIMAL" in hazards[0].message


def test_read_of_a_transient_never_written():
    plan = load("basic")
    plan["resources"].append({"name": "scratch", "kind": "buffer", "lifetime": "transient", "first": 0, "last": 0,
                              "bytes": 256, "heap": None, "offset": None, "initial": None, "final": None})
    pass_named(plan, "cull")["accesses"].append(
        {"resource": "scratch", "subresource": None, "usage": "uniform", "stages": ["COMPUTE_SHADER"],
         "access": ["UNIFORM_READ"], "layout": None, "write": False})
    hazards = check_plan(plan)
    assert [(h.kind, h.resource) for h in hazards] == [(UNDEFINED_CONTENTS, "scratch")]
    assert "read of undefined contents (never written this frame)" in hazards[0].message


def test_output_final_layout_must_match():
    plan = load("basic")
    resource_named(plan, "color")["final"]["layout"] = "SHADER_READ_ONLY_OPTIMAL"
    assert kinds(plan) == {FINAL_STATE}


def test_declared_lifetime_too_narrow():
    plan = load("basic")
    resource_named(plan, "depth")["last"] = 3  # 'post' (pass 4) still samples it
    (h,) = check_plan(plan)
    assert h.kind == LIFETIME and h.resource == "depth"


# --- subresources.json ------------------------------------------------------------------


def test_write_to_layer_0_does_not_need_a_barrier_for_layers_1_to_3():
    plan = load("subresources")
    read = pass_named(plan, "read_layers123")
    assert read["accesses"][0]["subresource"]["layers"] == [1, 4]
    assert all(b["subresource"]["layers"] == [1, 4] for b in read["barriers"])
    assert check_plan(plan) == []


def test_hazard_is_reported_only_on_the_uncovered_layer():
    plan = load("subresources")
    barrier_on(plan, "read_layers123", "cascades")["subresource"]["layers"] = [1, 3]
    hazards = check_plan(plan)
    assert hazards and {h.subresource for h in hazards} == {((0, 1), (3, 4))}
    assert {h.kind for h in hazards} >= {LAYOUT_MISMATCH, RAW}


def test_reading_layer_0_too_meets_the_color_write():
    plan = load("subresources")
    pass_named(plan, "read_layers123")["accesses"][0]["subresource"]["layers"] = [0, 4]
    hazards = check_plan(plan)
    assert {h.subresource for h in hazards} == {((0, 1), (0, 1))}
    at_read = [h for h in hazards if h.pass_name == "read_layers123"]
    assert {h.kind for h in at_read} == {LAYOUT_MISMATCH, RAW}
    assert any("write by pass 1 'draw_layer0'" in h.message for h in at_read)
    # and the later transition of layer 0 must now wait for that extra read
    assert [h.kind for h in hazards if h.pass_name == "show"] == [WAR]


def test_mip_chain_barrier_dropped_reports_only_that_mip():
    hazards = check_plan(without(load("subresources"), "mip2", "pyramid"))
    assert [(h.kind, h.subresource) for h in hazards] == [(RAW, ((1, 2), (0, 1)))]


# --- async_compute.json: two queues -------------------------------------------------------


def test_cross_queue_release_acquire_with_semaphores_is_clean():
    plan = load("async_compute")
    assert plan["queues"] == ["graphics", "compute"]
    assert check_plan(plan) == []


def test_cross_queue_without_semaphore_wait():
    plan = copy.deepcopy(load("async_compute"))
    pass_named(plan, "lighting")["waits"] = []
    hazards = check_plan(plan)
    assert QUEUE_OWNERSHIP in {h.kind for h in hazards}
    assert any("is not ordered before this acquire by a semaphore" in h.message for h in hazards)
    assert any(h.kind == RAW and "no semaphore ordering it" in h.message for h in hazards)


def test_acquire_without_release():
    hazards = check_plan(without(load("async_compute"), "depth_prepass", "depth", key="releases"))
    assert [h.kind for h in hazards] == [QUEUE_OWNERSHIP]
    assert "no matching release on queue 'graphics'" in hazards[0].message


def test_access_on_a_queue_that_does_not_own_the_resource():
    plan = without(without(load("async_compute"), "depth_prepass", "depth", key="releases"), "hbao", "depth")
    pass_named(plan, "hbao")["accesses"][0]["layout"] = "DEPTH_ATTACHMENT_OPTIMAL"
    hazards = check_plan(plan)
    owned = [h for h in hazards if h.kind == QUEUE_OWNERSHIP and h.pass_name == "hbao"]
    assert owned and "owned by queue 'graphics' (no ownership transfer to 'compute')" in owned[0].message


def test_wait_for_a_value_never_signalled():
    plan = load("async_compute")
    pass_named(plan, "lighting")["waits"][0]["value"] = 2
    hazards = check_plan(plan)
    assert hazards[0].kind == SEMAPHORE and "never signalled" in hazards[0].message


# --- aliasing.json ----------------------------------------------------------------------


def test_aliasing_overlap_when_lifetimes_intersect():
    plan = load("aliasing")
    resource_named(plan, "c")["offset"] = 0  # c is alive with a, same bytes
    hazards = check_plan(plan)
    assert ALIASING_OVERLAP in {h.kind for h in hazards}
    overlap = next(h for h in hazards if h.kind == ALIASING_OVERLAP)
    assert "'a'" in overlap.message and "'c'" in overlap.message


def test_aliasing_handoff_barrier_not_ordered_after_previous_occupant():
    plan = load("aliasing")
    barrier_on(plan, "draw_b", "b")["src"]["stages"] = []
    hazards = check_plan(plan)
    assert {h.kind for h in hazards} == {ALIASING_HANDOFF}
    messages = [h.message for h in hazards]
    assert any("from 'a': not ordered after read by pass 1 'read_a'" in m for m in messages)
    assert any("from 'a': not ordered after layout transition COLOR_ATTACHMENT_OPTIMAL" in m for m in messages)


def test_aliasing_handoff_missing_for_buffer():
    hazards = check_plan(without(load("aliasing"), "write_buf", "buf"))
    assert [h.kind for h in hazards] == [ALIASING_HANDOFF]
    assert "memory from 'b'" in hazards[0].message


def test_aliased_image_needs_a_transition_from_undefined():
    hazards = check_plan(without(load("aliasing"), "draw_b", "b"))
    assert {h.kind for h in hazards} >= {ALIASING_HANDOFF, LAYOUT_MISMATCH}


def test_older_occupant_fully_covered_by_a_newer_one_is_not_rechecked():
    # 'buf' covers a, b and c; 'a' was handed over to 'b', so only b and c are its previous occupants
    plan = load("aliasing")
    barrier_on(plan, "write_buf", "buf")["src"]["stages"] = []
    hazards = check_plan(plan)
    assert hazards and all("from 'a'" not in h.message for h in hazards)


# --- persistent.json ----------------------------------------------------------------------


def test_first_barrier_must_cover_the_previous_frames_write():
    plan = load("persistent")
    barrier_on(plan, "taa", "history")["src"]["access"] = []  # the transition must make it available
    hazards = check_plan(plan)
    assert [h.kind for h in hazards] == [WAW]
    assert "layout transition not ordered after write by the previous frame (ALL_TRANSFER/TRANSFER_WRITE)" \
        in hazards[0].message


def test_previous_frames_reads_need_a_war_barrier():
    plan = load("persistent")
    history = resource_named(plan, "history")
    for state in ("initial", "final"):
        history[state].update(stages=["COMPUTE_SHADER"], access=["SHADER_STORAGE_READ"])
    hazards = check_plan(plan)
    assert WAR in {h.kind for h in hazards}
    assert any("read by the previous frame (COMPUTE_SHADER/SHADER_STORAGE_READ)" in h.message for h in hazards)


def test_persistent_end_state_must_equal_its_start():
    plan = load("persistent")
    resource_named(plan, "history")["final"]["layout"] = "SHADER_READ_ONLY_OPTIMAL"
    assert kinds(plan) == {FINAL_STATE}


def test_final_state_must_cover_the_last_write():
    plan = load("persistent")
    resource_named(plan, "history")["final"].update(stages=["FRAGMENT_SHADER"], access=["SHADER_SAMPLED_READ"])
    hazards = check_plan(plan)
    assert {h.kind for h in hazards} == {FINAL_STATE}
    messages = [h.message for h in hazards]
    assert any("last write (ALL_TRANSFER/TRANSFER_WRITE) is not covered by 'final'" in m for m in messages)
    assert any("'initial' differs from 'final'" in m for m in messages)

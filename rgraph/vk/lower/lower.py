"""``lower(plan, queues) -> Recording``: what the runtime records for a plan, once, as data."""

from __future__ import annotations

from collections.abc import Iterable

from rgraph.plan.model import Plan
from rgraph.vk.lower.barriers import lower_barriers
from rgraph.vk.lower.batches import first_frame_releases, make_batches
from rgraph.vk.lower.model import Batch, PassRecording, Recording
from rgraph.vk.lower.queues import QueueLayout
from rgraph.vk.lower.semaphores import BatchSync, semaphore_edges, submission_order
from rgraph.vk.lower.workarounds import LAYER_WORKAROUNDS, check_names
from rgraph.vk.lower.workarounds.after_reads import src_additions
from rgraph.vk.lower.workarounds.layer_races import avoid_layer_races, touched_resources
from rgraph.vk.lower.workarounds.packed_ranges import partial_handoffs
from rgraph.vk.lower.workarounds.transfer_stages import widen_transfer_stages

SHARED_LIFETIMES = ("persistent", "imported")
ALL_COMMANDS = frozenset({"ALL_COMMANDS"})


class LoweringError(ValueError):
    """The plan's semaphores cannot be ordered (a wait for a later or missing signal, a cycle)."""


def lower(plan: Plan | dict, queues: QueueLayout, *, one_batch_per_pass: bool = False,
          workarounds: Iterable[str] = LAYER_WORKAROUNDS, batch_cuts: str = "queue") -> Recording:
    """The recording of ``plan`` on ``queues``: per pass its barrier calls, the batches (one
    command buffer each; ``one_batch_per_pass`` under validation, so that messages name the
    pass; ``batch_cuts``: ``rgraph.vk.lower.batches.make_batches``), the frame's semaphore
    edges and the host submission order. ``workarounds``: the
    validation-layer rewrites to apply (``rgraph.vk.lower.workarounds``; () for none).

    ``plan`` is a typed ``rgraph.plan.Plan`` or its JSON document; the rewrites read the
    document (``Recording.plan`` is the document the runtime executes)."""
    if isinstance(plan, Plan):
        plan = plan.to_json_dict()
    enabled = check_names(tuple(workarounds))
    disabled = [name for name in LAYER_WORKAROUNDS if name not in enabled]
    if "transfer_stages" in enabled:
        plan = widen_transfer_stages(plan)
    families = dict(queues.families)
    key = queues.family
    additions = (src_additions(plan, key) if "name_read_write" in enabled
                 else [{} for _ in plan["passes"]])
    handoffs = (partial_handoffs(plan) if "packed_range_global_barrier" in enabled
                else [set() for _ in plan["passes"]])
    passes = []
    for i, p in enumerate(plan["passes"]):
        caps = queues.capabilities_of(p["queue"])
        waited = [st for w in p["waits"] if not queues.same_queue(w["queue"], p["queue"]) for st in w["stages"]]
        before = lower_barriers(p["barriers"], "barrier", families, waited, caps, additions[i], handoffs[i], disabled)
        after = lower_barriers(p["releases"], "release", families, (), caps, None, frozenset(), disabled)
        passes.append(PassRecording(i, p["name"], p["queue"], tuple(map(tuple, before)), tuple(map(tuple, after))))
    plan_batches = make_batches(plan, queues, one_per_pass=one_batch_per_pass, cuts=batch_cuts)
    index_of = {id(p): i for i, p in enumerate(plan["passes"])}
    batches = tuple(Batch(b.queue, tuple(index_of[id(p)] for p in b.passes)) for b in plan_batches)
    syncs = [BatchSync(b.queue, key(b.queue),
                       tuple((w["queue"], w["value"], frozenset(w["stages"])) for w in b.passes[0]["waits"]
                             if not queues.same_queue(w["queue"], b.queue)),  # one VkQueue: no semaphore
                       tuple((s["queue"], s["value"], frozenset(s["stages"])) for s in b.passes[-1]["signals"]),
                       touched_resources(b.passes))
             for b in plan_batches]
    try:
        if "layer_race_edges" in enabled:
            edges, order, layer_edges = avoid_layer_races(syncs, ALL_COMMANDS)
        else:
            edges = semaphore_edges(syncs, ALL_COMMANDS)
            order, layer_edges = submission_order(syncs, edges), 0
    except ValueError as exc:
        raise LoweringError(f"plan semaphores: {exc}") from None
    shared = {r["name"] for r in plan["resources"] if r["lifetime"] in SHARED_LIFETIMES}
    first = {}
    for queue, releases in first_frame_releases(plan, shared).items():
        calls = lower_barriers(releases, "release", families, (), queues.capabilities_of(queue), None, frozenset(),
                               disabled)
        if calls:
            first[queue] = tuple(map(tuple, calls))
    return Recording(plan, queues, tuple(passes), batches, tuple(edges), tuple(order), first, layer_edges, enabled)

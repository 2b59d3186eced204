"""The racing false positive of Khronos validation 1.3.239 across queues, modelled, and the
semaphore edges that avoid it.

The layer's submit-time check (as observed on an H100) tests a batch on VkQueue X against
the last submitted batch of every other VkQueue Y that X has not waited for, and counts in
that batch's access context every access tagged after X's last sync with Y - including X's
own accesses that Y imported through a wait. So X touching a resource again, after Y waited
for X's earlier access and before X waits for Y, is reported as racing Y although only X's
queue order stands between the two accesses. Submission order alone cannot always avoid it
(about 3-4% of random multi-queue graphs keep a report under every order tried).

``avoid_layer_races`` therefore adds, where the model predicts a report, one real semaphore
edge from Y's last batch to the reported batch: a dependency that the plan does not need but
that is harmless (it goes forward in a valid submission order, so it closes no cycle) and
makes the layer see the sync. The model treats every access as a write (layout transitions
are) and resources as whole (the layer of that version tracks no aliasing), so it can only
over-predict; over-prediction costs a little overlap, never correctness. Plans whose
batches the model finds clean (every bundled graph) get no extra edge.
"""

from __future__ import annotations

from rgraph.vk.lower.semaphores import BatchSync, SemaphoreEdge, semaphore_edges, submission_order

MODEL_FRAMES = 3  # frame 0 has no previous frame; frames 1 and 2 are the steady state for both sets


def touched_resources(passes: list[dict]) -> frozenset[str]:
    """Resources a batch's passes access or name in a barrier (a transition is an access)."""
    return frozenset(a["resource"] for p in passes for a in (*p["accesses"], *p["barriers"]))


def racing_batches(batches: list[BatchSync], edges: list[SemaphoreEdge], order: list[int],
                   frames: int = MODEL_FRAMES) -> list[tuple[int, int]]:
    """(reported batch, batch of the other queue it is checked against), in submission order
    over ``frames`` frames, each pair once."""
    queues = {b.vk_queue for b in batches}
    ctx: dict = {q: {} for q in queues}  # queue -> resource -> tag of the last access it knows of
    synced: dict = {q: {} for q in queues}  # queue -> other queue -> tag it has synced with
    snapshot: dict = {}  # (batch, frame) -> (ctx, synced, tag) at its signal
    last: dict = {}  # queue -> (batch, ctx, tag) of its last submitted batch
    waits_of: dict[int, list[SemaphoreEdge]] = {}
    for e in edges:
        waits_of.setdefault(e.wait_batch, []).append(e)
    tag = 0
    reports: list[tuple[int, int]] = []
    for frame in range(frames):
        for bi in order:
            x = batches[bi].vk_queue
            for e in waits_of.get(bi, ()):
                key = (e.signal_batch, frame - 1 if e.frame_edge else frame)
                if key not in snapshot:
                    continue
                sctx, ssync, stag = snapshot[key]
                for r, t in sctx.items():
                    ctx[x][r] = max(ctx[x].get(r, -1), t)
                for q, t in ssync.items():
                    synced[x][q] = max(synced[x].get(q, -1), t)
                y = batches[e.signal_batch].vk_queue
                synced[x][y] = max(synced[x].get(y, -1), stag)
            tag += 1
            for y, (yb, yctx, ytag) in last.items():
                seen = synced[x].get(y, -1)
                if y == x or ytag <= seen:
                    continue
                if any(yctx.get(r, -1) > seen for r in batches[bi].resources) and (bi, yb) not in reports:
                    reports.append((bi, yb))
            for r in batches[bi].resources:
                ctx[x][r] = tag
            synced[x][x] = tag
            snapshot[(bi, frame)] = (dict(ctx[x]), dict(synced[x]), tag)
            last[x] = (bi, dict(ctx[x]), tag)
    return reports


def avoid_layer_races(batches: list[BatchSync], all_commands: int) -> tuple[list[SemaphoreEdge], list[int], int]:
    """(edges, submission order, extra edges added): the frame's semaphore edges plus, one at
    a time, an edge for the first report the model predicts, until it predicts none."""
    extra: list[tuple[int, int]] = []
    while True:
        edges = semaphore_edges(batches, all_commands, extra)
        order = submission_order(batches, edges)
        reports = racing_batches(batches, edges, order)
        if not reports:
            return edges, order, len(extra)
        waiting, signalling = reports[0]
        if (signalling, waiting) in extra:  # cannot happen: the edge syncs exactly that pair
            raise ValueError(f"layer race model: edge {signalling} -> {waiting} did not sync the pair")
        extra.append((signalling, waiting))

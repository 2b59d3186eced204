"""The lowered recording as text (``rgraph inspect PLAN --lowered``): every
vkCmdPipelineBarrier2 per pass, the batches, the semaphore edges and the submit order."""

from __future__ import annotations

from rgraph.vk.lower.model import BarrierSpec, Recording


def _names(items) -> str:
    return "|".join(sorted(items)) or "NONE"


def _family(index: int | None) -> str:
    return "IGNORED" if index is None else str(index)


def format_spec(spec: BarrierSpec) -> str:
    scope = (f"{_names(spec.src_stages)}/{_names(spec.src_access)} -> "
             f"{_names(spec.dst_stages)}/{_names(spec.dst_access)}")
    if spec.resource is None:
        return f"memory  {scope}"
    where = spec.resource
    if spec.subresource is not None:
        sub = spec.subresource
        where += f" mips {sub['mips'][0]}:{sub['mips'][1]} layers {sub['layers'][0]}:{sub['layers'][1]}"
    kind = "image " if spec.subresource is not None else "buffer"
    text = f"{kind}  {where}  {scope}"
    if spec.subresource is not None:
        text += f"  {spec.old_layout} -> {spec.new_layout}"
    if spec.src_family is not None or spec.dst_family is not None:
        text += f"  family {_family(spec.src_family)} -> {_family(spec.dst_family)}"
    return text


def _calls(label: str, calls) -> list[str]:
    lines = []
    for n, call in enumerate(calls):
        lines.append(f"    {label} call {n + 1}:")
        lines += [f"      {format_spec(s)}" for s in call]
    return lines


def format_recording(rec: Recording) -> str:
    """Every line ``rgraph inspect --lowered`` prints."""
    lines = [f"queues: {rec.queues.source}",
             "layer workarounds: " + (", ".join(rec.workarounds) if rec.workarounds else "none"),
             f"{len(rec.passes)} passes, {rec.calls()} vkCmdPipelineBarrier2 calls per frame, "
             f"{len(rec.batches)} batches, {len(rec.edges)} semaphore edges"
             + (f" ({rec.layer_edges} added for the layer)" if rec.layer_edges else ""),
             "submit order: " + " ".join(f"batch {b}" for b in rec.order), ""]
    for p in rec.passes:
        lines.append(f"pass {p.index} {p.name}  [{p.queue}, family {rec.queues.family(p.queue)}]")
        lines += _calls("before", p.before) + _calls("after", p.after)
        if not p.before and not p.after:
            lines.append("    no barriers")
    lines.append("")
    for bi, batch in enumerate(rec.batches):
        names = ", ".join(rec.passes[i].name for i in batch.passes)
        lines.append(f"batch {bi} on {batch.queue} (family {rec.queues.family(batch.queue)}): {names}")
    for e in rec.edges:
        kind = "frame edge (previous frame)" if e.frame_edge else "in frame"
        lines.append(f"semaphore: batch {e.signal_batch} signals {_names(e.signal_stages)} -> batch {e.wait_batch} "
                     f"waits {_names(e.wait_stages)}, {kind}")
    for queue, calls in sorted(rec.first_frame.items()):
        lines.append(f"before frame 0 on {queue}:")
        lines += _calls("release", calls)
    return "\n".join(lines) + "\n"

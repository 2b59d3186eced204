"""The plan (docs/plan.md, FORMAT.md section 3) as a typed, immutable model.

    from rgraph import plan as rplan
    p = rplan.load("plan.json")        # or load(json_text); RGraphError (located) if malformed
    p.passes[3].barriers[0].src.layout
    text = rplan.dump(p)               # canonical JSON, byte-identical to what compile writes

Classes (``rgraph.plan.model``), one per JSON object; field names are the JSON keys
(``pass`` is ``pass_name``), lists are tuples, free-form objects read-only mappings:

- ``Plan``: the document. ``resource(name)``, ``resource_by_name``, ``heap_by_id``;
  ``absent`` names top-level keys older plans lack (``features``, ``outputs``,
  ``scene_source``), so ``dump`` reproduces them.
- ``PlanPass``: ``accesses`` (``Access``), ``barriers``/``releases`` (``Barrier``),
  ``waits`` (``Wait``), ``signals`` (``Signal``).
- ``Barrier``: ``src``/``dst`` (``State``), ``subresource`` (``Subresource`` or None for
  buffers), ``aliases`` (always a tuple; JSON keeps a name, a list, or null).
- ``PlanResource``: ``initial``/``final`` are a ``State``, a tuple of ``CellState``
  (non-uniform) or None; ``buffer_bytes`` is ``size_bytes or bytes``.
- ``Heap``, ``Culled``, ``DroppedRead``, ``Stats`` (None = key not in the file).

``load`` checks shape (keys, types, bounded integers, shallow params) and consistency
(passes' ``index``, queues, referenced resources and heaps, subresource bounds) and raises
``RGraphError`` with ``FILE:LINE:COL: error: malformed plan: JSON.PATH: ...``.
``rgraph check`` keeps its own, independent reader (``rgraph.check.plan``).
"""

from rgraph.plan.dump import aliases_json, dump, dumps_json, to_json_dict
from rgraph.plan.model import (
    PLAN_FORMAT,
    QUEUE_ORDER,
    Access,
    Barrier,
    CellState,
    Culled,
    DroppedRead,
    EndState,
    Heap,
    Plan,
    PlanPass,
    PlanResource,
    Signal,
    State,
    Stats,
    Subresource,
    Wait,
)
from rgraph.plan.read import from_json_dict, load, parse, read_text

__all__ = [
    "PLAN_FORMAT", "QUEUE_ORDER", "Access", "Barrier", "CellState", "Culled", "DroppedRead", "EndState", "Heap",
    "Plan", "PlanPass", "PlanResource", "Signal", "State", "Stats", "Subresource", "Wait",
    "aliases_json", "dump", "dumps_json", "from_json_dict", "load", "parse", "read_text", "to_json_dict",
]

"""The plan as frozen dataclasses: one class per JSON object of docs/plan.md.

Field names are the JSON keys, except ``pass`` (``pass_name``). Lists are tuples,
objects that are free-form (``params``, ``features``) are read-only mappings, and a
barrier's ``aliases`` is always a tuple (JSON: a name, a list or null).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import Any

PLAN_FORMAT = "rgraph-plan/1"
#: Plan queues in the order ``queues`` lists them.
QUEUE_ORDER = ("graphics", "compute", "transfer")
LIFETIMES = ("transient", "persistent", "imported", "output")
RESOURCE_KINDS = ("image", "buffer", "accel")
#: Top-level keys that plans written before they existed lack; ``Plan.absent`` names them.
OPTIONAL_TOP_KEYS = ("features", "outputs", "scene_source")
#: A resource's image-only keys (compile writes them for images only).
IMAGE_KEYS = ("extent", "mips", "layers", "samples")

Range = tuple[int, int]
Names = tuple[str, ...]
EMPTY: Mapping[str, Any] = MappingProxyType({})


@dataclass(frozen=True, slots=True)
class Subresource:
    """Half-open mip and layer ranges ``[begin, end)`` of an image."""

    mips: Range
    layers: Range


@dataclass(frozen=True, slots=True)
class State:
    """A sync2 state: stages, accesses (writes only in a barrier's ``src``), layout, queue."""

    stages: Names
    access: Names
    layout: str | None
    queue: str | None  # None: no queue has touched it yet (a transient's initial state)


@dataclass(frozen=True, slots=True)
class CellState:
    """One cell's end state in a non-uniform ``initial``/``final`` list."""

    subresource: Subresource
    state: State


#: ``initial``/``final``: one state, one per cell (non-uniform), or null.
EndState = State | tuple[CellState, ...] | None


@dataclass(frozen=True, slots=True)
class Access:
    resource: str
    subresource: Subresource | None  # None for buffers
    usage: str
    stages: Names
    access: Names
    layout: str | None
    write: bool


@dataclass(frozen=True, slots=True)
class Barrier:
    resource: str
    subresource: Subresource | None
    src: State
    dst: State
    aliases: Names = ()  # previous occupants of aliased memory this barrier hands over

    @property
    def is_ownership_transfer(self) -> bool:
        return self.src.queue != self.dst.queue


@dataclass(frozen=True, slots=True)
class TimelineValue:
    """A value of queue ``queue``'s timeline semaphore and a stage mask (``Wait``, ``Signal``)."""

    queue: str
    value: int
    stages: Names
    device: int | None = None  # a cross-device wait names the other device (JSON key only when set)


@dataclass(frozen=True, slots=True)
class Wait(TimelineValue):
    """Wait for ``queue``'s timeline to reach ``value`` before the pass; ``stages``: dst stage mask."""


@dataclass(frozen=True, slots=True)
class Signal(TimelineValue):
    """Signal this pass's queue's timeline to ``value`` after the pass; ``stages``: src stage mask."""


@dataclass(frozen=True, slots=True)
class PlanPass:
    name: str
    index: int
    device: int
    queue: str
    kind: str
    impl: str | None  # registered implementation; None = the probe
    params: Mapping[str, Any]
    accesses: tuple[Access, ...]
    barriers: tuple[Barrier, ...]  # before the pass
    releases: tuple[Barrier, ...]  # queue-family releases after the pass
    waits: tuple[Wait, ...]
    signals: tuple[Signal, ...]


@dataclass(frozen=True, slots=True)
class PlanResource:
    name: str
    kind: str
    format: str | None
    bytes: int  # memory size
    size_bytes: int | None  # buffers: requested size
    alignment: int
    memory_type_bits: int
    memory_class: str
    usages: Names
    lifetime: str
    first: int | None
    last: int | None
    heap: int | None  # None (with offset None): not placed (hand-written plans)
    offset: int | None
    initial: EndState
    final: EndState
    extent: tuple[int, int, int] | None = None  # images (with mips, layers, samples)
    mips: int | None = None
    layers: int | None = None
    samples: int | None = None
    #: accels: the sized layout (``rgraph.compiler.accel.AccelLayout.as_plan``), in file order
    accel: Mapping[str, Any] | None = None
    #: an accel's build scratch buffer: the accel's name
    scratch_of: str | None = None
    #: which of IMAGE_KEYS the file lacked; None: all four iff ``extent`` is None (what compile writes)
    absent: frozenset[str] | None = None
    device: int = 0  # the device that owns it (multi-device plans; JSON key only when != 0)

    @property
    def is_image(self) -> bool:
        return self.kind == "image"

    @property
    def buffer_bytes(self) -> int:
        """The size a buffer is created with: ``size_bytes``, else the memory size."""
        return self.size_bytes or self.bytes


@dataclass(frozen=True, slots=True)
class Heap:
    id: int
    bytes: int
    memory_class: str
    alignment: int
    device: int = 0  # the device whose memory it is (JSON key only when != 0)


@dataclass(frozen=True, slots=True)
class Culled:
    """A culled pass, with the resources only culled passes used and their bytes."""

    pass_name: str
    reason: str
    resources: Names
    bytes: int


@dataclass(frozen=True, slots=True)
class DroppedRead:
    pass_name: str
    resource: str
    reason: str


@dataclass(frozen=True, slots=True)
class Stats:
    """Plan totals; None = not in the file (hand-written plans carry only some)."""

    barriers: int | None = None
    semaphores: int | None = None
    peak_bytes: int | None = None
    lower_bound_bytes: int | None = None
    unaliased_bytes: int | None = None
    allocations: int | None = None
    policy: str | None = None
    sync: str | None = None  # "naive" for --sync naive plans
    schedule: str | None = None  # the --schedule mode when not the default (declaration order)


@dataclass(frozen=True)
class Plan:
    """A whole plan (docs/plan.md). ``rgraph.plan.load`` builds one, ``dump`` writes it."""

    graph: str
    source: str | None
    scene: str | None
    size: tuple[int, int]
    params: Mapping[str, Any]
    device_profile: str
    queues: Names
    passes: tuple[PlanPass, ...]
    culled: tuple[Culled, ...]
    dropped_reads: tuple[DroppedRead, ...]
    resources: tuple[PlanResource, ...]  # sorted by name
    heaps: tuple[Heap, ...]
    stats: Stats
    features: Mapping[str, Any] = field(default_factory=lambda: EMPTY)
    outputs: Names = ()
    scene_source: str | None = None
    camera: int = 0  # ``--camera N`` (FORMAT.md 7); written only when not 0
    #: ``{"devices": N, "split": ..., "balance": ..., ...}`` for multi-device plans (FORMAT.md 6), else None
    multi_device: Mapping[str, Any] | None = None
    format: str = PLAN_FORMAT
    #: keys of OPTIONAL_TOP_KEYS the file did not have (older plans); ``dump`` leaves them out
    absent: frozenset[str] = field(default=frozenset())

    @cached_property
    def resource_by_name(self) -> Mapping[str, PlanResource]:
        return MappingProxyType({r.name: r for r in self.resources})

    @cached_property
    def heap_by_id(self) -> Mapping[int, Heap]:
        return MappingProxyType({h.id: h for h in self.heaps})

    def resource(self, name: str) -> PlanResource:
        return self.resource_by_name[name]

    @property
    def barrier_count(self) -> int:
        return sum(len(p.barriers) for p in self.passes)

    def to_json_dict(self) -> dict[str, Any]:
        """The decoded JSON document (fresh, mutable): for code that still reads plan dicts."""
        from rgraph.plan.dump import to_json_dict

        return to_json_dict(self)

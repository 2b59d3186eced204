"""Read a plan dict (docs/plan.md) into the checker's own small model.

Only what the replay needs is kept. Stage and access names become concrete bit masks
(meta names expanded); queues become small integers. A malformed plan raises
``PlanShapeError`` with the JSON path of the offending value.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rgraph.check import vocab
from rgraph.errors import quote
from rgraph.jsonloc import PathPart, format_path

Rect = tuple[int, int, int, int]  # mip begin, mip end, layer begin, layer end (half-open)
LIFETIMES = ("transient", "persistent", "imported", "output")


class PlanShapeError(Exception):
    """The plan does not have the documented shape; ``path`` locates the value."""

    def __init__(self, path: list[PathPart], message: str) -> None:
        super().__init__(f"{format_path(path)}: {message}")
        self.path = path
        self.message = message


@dataclass(slots=True)
class Scope:
    """One side of a barrier."""

    stages: int
    access: int
    layout: str | None
    queue: int


@dataclass(slots=True)
class Barrier:
    resource: int  # index into Plan.resources; -1 = global memory barrier
    rect: Rect | None
    src: Scope
    dst: Scope
    aliases: tuple[str, ...] | None  # previous occupants handed over (informational)
    position: int  # index in its list

    @property
    def is_transfer(self) -> bool:
        return self.src.queue != self.dst.queue

    @property
    def is_transition(self) -> bool:
        return self.src.layout != self.dst.layout


@dataclass(slots=True)
class Access:
    resource: int
    rect: Rect | None
    stages: int
    access: int
    layout: str | None
    write: bool
    usage: str

    @property
    def read_bits(self) -> int:
        return self.access & vocab.READ_MASK

    @property
    def write_bits(self) -> int:
        if not self.write:
            return self.access & vocab.WRITE_MASK
        return (self.access & vocab.WRITE_MASK) or self.access


@dataclass(slots=True)
class SemaphoreOp:
    queue: int
    value: int
    stages: int = vocab.ALL_STAGES  # a wait's second synchronization scope (a signal's first)


@dataclass(slots=True)
class Pass:
    index: int
    name: str
    queue: int
    accesses: list[Access]
    barriers: list[Barrier]
    releases: list[Barrier]
    waits: list[SemaphoreOp]
    signals: list[SemaphoreOp]

    @property
    def label(self) -> str:
        return f"pass {self.index} '{self.name}'"


@dataclass(slots=True)
class EndState:
    """A resource's state at a frame boundary, for ``rect`` (None: every cell)."""

    rect: Rect | None
    stages: int
    access: int
    layout: str | None
    queue: int | None
    raw: dict[str, Any]
    index: int | None = None  # position in a per-subresource list


@dataclass(slots=True)
class Resource:
    name: str
    kind: str  # image | buffer | accel
    mips: int
    layers: int
    lifetime: str
    first: int | None
    last: int | None
    heap: int | None
    offset: int | None
    bytes: int | None
    initial: list[EndState] | None  # one entry, or one per cell group (non-uniform end states)
    final: list[EndState] | None

    @property
    def is_image(self) -> bool:
        return self.kind == "image"

    @property
    def whole(self) -> Rect:
        return (0, self.mips, 0, self.layers)


@dataclass(slots=True)
class Plan:
    queues: list[str]
    passes: list[Pass]
    resources: list[Resource]
    resource_index: dict[str, int] = field(default_factory=dict)


# --- reading -------------------------------------------------------------------------


def _fail(path: list[PathPart], message: str) -> PlanShapeError:
    return PlanShapeError(path, message)


def _obj(value: Any, path: list[PathPart]) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise _fail(path, f"expected an object, got {type(value).__name__}")
    return value


def _list(value: Any, path: list[PathPart]) -> list[Any]:
    if not isinstance(value, list):
        raise _fail(path, f"expected a list, got {type(value).__name__}")
    return value


def _get(obj: dict[str, Any], key: str, path: list[PathPart], default: Any = ..., ) -> Any:
    if key not in obj:
        if default is ...:
            raise _fail(path, f"missing key '{key}'")
        return default
    return obj[key]


def _int(value: Any, path: list[PathPart], allow_none: bool = False) -> int | None:
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, int):
        raise _fail(path, f"expected an integer, got {quote(value)}")
    return value


def _str(value: Any, path: list[PathPart], allow_none: bool = False) -> str | None:
    if value is None and allow_none:
        return None
    if not isinstance(value, str):
        raise _fail(path, f"expected a string, got {quote(value)}")
    return value


def _names(value: Any, path: list[PathPart], known: frozenset[str], what: str) -> list[str]:
    items = _list(value, path)
    try:
        if known.issuperset(items):
            return items
    except TypeError:  # an unhashable item: report it below
        pass
    for i, name in enumerate(items):
        if not isinstance(name, str) or name not in known:
            raise _fail(path + [i], f"unknown {what} name {quote(name)}")
    return items


class _Reader:
    def __init__(self, raw: dict[str, Any]) -> None:
        self.raw = raw
        self.queue_ids: dict[str, int] = {}
        self.queue_names: list[str] = []

    def queue(self, value: Any, path: list[PathPart]) -> int:
        name = _str(value, path)
        assert name is not None
        if name not in self.queue_ids:
            if "queues" in self.raw:
                raise _fail(path, f"queue '{name}' is not in the plan's 'queues'")
            self.queue_ids[name] = len(self.queue_names)
            self.queue_names.append(name)
        return self.queue_ids[name]

    def layout(self, value: Any, path: list[PathPart]) -> str | None:
        name = _str(value, path, allow_none=True)
        if name is not None and name not in vocab.LAYOUTS:
            raise _fail(path, f"unknown image layout {quote(name)}")
        return name

    def rect(self, value: Any, path: list[PathPart]) -> Rect | None:
        if value is None:
            return None
        sub = _obj(value, path)
        out: list[int] = []
        for key in ("mips", "layers"):
            pair = _list(_get(sub, key, path), path + [key])
            if len(pair) != 2:
                raise _fail(path + [key], "expected [begin, end]")
            begin = _int(pair[0], path + [key, 0])
            end = _int(pair[1], path + [key, 1])
            assert begin is not None and end is not None
            if not 0 <= begin < end:
                raise _fail(path + [key], f"empty or negative range [{begin}, {end})")
            out += [begin, end]
        return (out[0], out[1], out[2], out[3])

    def scope(self, value: Any, path: list[PathPart], position: str) -> Scope:
        raw = _obj(value, path)
        stages = _names(_get(raw, "stages", path), path + ["stages"], vocab.KNOWN_STAGE_NAMES, "stage")
        access = _names(_get(raw, "access", path), path + ["access"], vocab.KNOWN_ACCESS_NAMES, "access")
        return Scope(
            stages=vocab.stage_mask(stages, position),
            access=vocab.access_mask(access),
            layout=self.layout(_get(raw, "layout", path, None), path + ["layout"]),
            queue=self.queue(_get(raw, "queue", path), path + ["queue"]),
        )

    def end_states(self, value: Any, path: list[PathPart]) -> list[EndState] | None:
        """One state (an object) or a list of per-subresource states; None stays None."""
        if value is None:
            return None
        if isinstance(value, list):
            return [self.end_state(item, path + [i], i) for i, item in enumerate(value)]
        return [self.end_state(value, path, None)]

    def end_state(self, value: Any, path: list[PathPart], index: int | None) -> EndState:
        raw = _obj(value, path)
        stages = _names(_get(raw, "stages", path, []), path + ["stages"], vocab.KNOWN_STAGE_NAMES, "stage")
        access = _names(_get(raw, "access", path, []), path + ["access"], vocab.KNOWN_ACCESS_NAMES, "access")
        queue = _get(raw, "queue", path, None)
        rect = self.rect(_get(raw, "subresource", path, None), path + ["subresource"])
        if index is not None and rect is None and "subresource" not in raw:
            raise _fail(path, "a per-subresource end state needs 'subresource'")
        return EndState(
            rect=rect,
            stages=vocab.stage_mask(stages, vocab.SCOPE_ACCESS),
            access=vocab.access_mask(access),
            layout=self.layout(_get(raw, "layout", path, None), path + ["layout"]),
            queue=None if queue is None else self.queue(queue, path + ["queue"]),
            raw=raw,
            index=index,
        )


def _aliases(value: Any, path: list[PathPart]) -> tuple[str, ...] | None:
    if value is None:
        return None
    if isinstance(value, str):
        return (value,)
    items = _list(value, path)
    for i, name in enumerate(items):
        _str(name, path + [i])
    return tuple(items)


def read_plan(raw: Any) -> Plan:
    """The checker's model of a plan dict; ``PlanShapeError`` if it is malformed."""
    top = _obj(raw, [])
    fmt = top.get("format")
    if fmt is not None and fmt != "rgraph-plan/1":
        raise _fail(["format"], f"unsupported plan format {quote(fmt)} (expected 'rgraph-plan/1')")
    reader = _Reader(top)
    if "queues" in top:
        for i, name in enumerate(_list(top["queues"], ["queues"])):
            name = _str(name, ["queues", i])
            assert name is not None
            if name in reader.queue_ids:
                raise _fail(["queues", i], f"queue '{name}' listed twice")
            reader.queue_ids[name] = len(reader.queue_names)
            reader.queue_names.append(name)

    raw_resources = _list(_get(top, "resources", []), ["resources"])
    raw_passes = _list(_get(top, "passes", []), ["passes"])
    names: dict[str, int] = {}
    for i, res in enumerate(raw_resources):
        res = _obj(res, ["resources", i])
        name = _str(_get(res, "name", ["resources", i]), ["resources", i, "name"])
        assert name is not None
        if name in names:
            raise _fail(["resources", i, "name"], f"resource '{name}' defined twice")
        names[name] = i

    def resource_ref(value: Any, path: list[PathPart]) -> int:
        name = _str(value, path)
        if name not in names:
            raise _fail(path, f"unknown resource {quote(name)}")
        return names[name]

    passes: list[Pass] = []
    extents: dict[int, list[int]] = {}  # resource -> [max mip end, max layer end, has subresource]

    def note_rect(res: int, rect: Rect | None) -> None:
        ext = extents.setdefault(res, [0, 0, 0])
        if rect is not None:
            ext[0] = max(ext[0], rect[1])
            ext[1] = max(ext[1], rect[3])
            ext[2] = 1

    def barrier(value: Any, path: list[PathPart], position: int) -> Barrier:
        raw_b = _obj(value, path)
        res_value = _get(raw_b, "resource", path)
        res = -1 if res_value is None else resource_ref(res_value, path + ["resource"])
        rect = reader.rect(_get(raw_b, "subresource", path, None), path + ["subresource"])
        if res >= 0:
            note_rect(res, rect)
        return Barrier(
            resource=res,
            rect=rect,
            src=reader.scope(_get(raw_b, "src", path), path + ["src"], vocab.SCOPE_FIRST),
            dst=reader.scope(_get(raw_b, "dst", path), path + ["dst"], vocab.SCOPE_SECOND),
            aliases=_aliases(raw_b.get("aliases"), path + ["aliases"]),
            position=position,
        )

    def semaphore(value: Any, path: list[PathPart], scope: str = vocab.SCOPE_SECOND) -> SemaphoreOp:
        raw_s = _obj(value, path)
        names = _names(_get(raw_s, "stages", path, []), path + ["stages"], vocab.KNOWN_STAGE_NAMES, "stage")
        value_int = _int(_get(raw_s, "value", path), path + ["value"])
        assert value_int is not None
        stages = vocab.stage_mask(names, scope) if names else vocab.ALL_STAGES  # none given: ALL_COMMANDS
        return SemaphoreOp(queue=reader.queue(_get(raw_s, "queue", path), path + ["queue"]), value=value_int,
                           stages=stages)

    for i, raw_p in enumerate(raw_passes):
        at: list[PathPart] = ["passes", i]
        p = _obj(raw_p, at)
        index = _int(_get(p, "index", at, i), at + ["index"])
        if index != i:
            raise _fail(at + ["index"], f"pass index {index} is not its position {i}")
        accesses = []
        for j, raw_a in enumerate(_list(_get(p, "accesses", at, []), at + ["accesses"])):
            apath = at + ["accesses", j]
            a = _obj(raw_a, apath)
            res = resource_ref(_get(a, "resource", apath), apath + ["resource"])
            rect = reader.rect(_get(a, "subresource", apath, None), apath + ["subresource"])
            note_rect(res, rect)
            stage_list = _names(_get(a, "stages", apath), apath + ["stages"], vocab.KNOWN_STAGE_NAMES, "stage")
            stages = vocab.stage_mask(stage_list, vocab.SCOPE_ACCESS)
            if stages == 0:
                raise _fail(apath + ["stages"], "an access needs at least one pipeline stage")
            access_list = _names(_get(a, "access", apath), apath + ["access"], vocab.KNOWN_ACCESS_NAMES, "access")
            write = _get(a, "write", apath, None)
            if write is not None and not isinstance(write, bool):
                raise _fail(apath + ["write"], f"expected true or false, got {quote(write)}")
            access_bits = vocab.access_mask(access_list)
            accesses.append(Access(
                resource=res, rect=rect, stages=stages, access=access_bits,
                layout=reader.layout(_get(a, "layout", apath, None), apath + ["layout"]),
                write=bool(access_bits & vocab.WRITE_MASK) if write is None else write,
                usage=str(a.get("usage") or ""),
            ))
        passes.append(Pass(
            index=i,
            name=str(_str(_get(p, "name", at), at + ["name"])),
            queue=reader.queue(_get(p, "queue", at, "graphics"), at + ["queue"]),
            accesses=accesses,
            barriers=[barrier(b, at + ["barriers", k], k)
                      for k, b in enumerate(_list(_get(p, "barriers", at, []), at + ["barriers"]))],
            releases=[barrier(b, at + ["releases", k], k)
                      for k, b in enumerate(_list(_get(p, "releases", at, []), at + ["releases"]))],
            waits=[semaphore(w, at + ["waits", k])
                   for k, w in enumerate(_list(_get(p, "waits", at, []), at + ["waits"]))],
            signals=[semaphore(s, at + ["signals", k], vocab.SCOPE_FIRST)
                     for k, s in enumerate(_list(_get(p, "signals", at, []), at + ["signals"]))],
        ))

    resources: list[Resource] = []
    for i, raw_r in enumerate(raw_resources):
        at = ["resources", i]
        r = raw_r
        ext = extents.get(i, [0, 0, 0])
        kind = _str(_get(r, "kind", at, "image" if ext[2] else "buffer"), at + ["kind"])
        if kind not in ("image", "buffer", "accel"):
            raise _fail(at + ["kind"], f"unknown resource kind {quote(kind)}")
        lifetime = _str(_get(r, "lifetime", at, "transient"), at + ["lifetime"])
        if lifetime not in LIFETIMES:
            raise _fail(at + ["lifetime"], f"unknown lifetime {quote(lifetime)}")
        if kind == "image":
            mips = _int(_get(r, "mips", at, max(ext[0], 1)), at + ["mips"])
            layers = _int(_get(r, "layers", at, max(ext[1], 1)), at + ["layers"])
        else:
            mips = layers = 1
        assert mips is not None and layers is not None
        if mips < 1 or layers < 1:
            raise _fail(at, "an image needs at least one mip and one layer")
        initial = reader.end_states(_get(r, "initial", at, None), at + ["initial"])
        if lifetime in ("persistent", "imported") and initial is None:
            raise _fail(at, f"a {lifetime} resource needs an 'initial' state")
        resources.append(Resource(
            name=str(r["name"]), kind=str(kind), mips=mips, layers=layers, lifetime=str(lifetime),
            first=_int(_get(r, "first", at, None), at + ["first"], allow_none=True),
            last=_int(_get(r, "last", at, None), at + ["last"], allow_none=True),
            heap=_int(_get(r, "heap", at, None), at + ["heap"], allow_none=True),
            offset=_int(_get(r, "offset", at, None), at + ["offset"], allow_none=True),
            bytes=_int(_get(r, "bytes", at, None), at + ["bytes"], allow_none=True),
            initial=initial,
            final=reader.end_states(_get(r, "final", at, None), at + ["final"]),
        ))

    _check_rects(passes, resources)
    return Plan(queues=reader.queue_names, passes=passes, resources=resources, resource_index=names)


def _check_rects(passes: list[Pass], resources: list[Resource]) -> None:
    """Subresource ranges must lie inside their image; buffers take none."""

    def check(res_index: int, rect: Rect | None, path: list[PathPart]) -> None:
        if res_index < 0:
            return
        res = resources[res_index]
        if rect is None:
            return
        if not res.is_image:
            raise _fail(path, f"'{res.name}' is a {res.kind}: its subresource must be null")
        if rect[1] > res.mips or rect[3] > res.layers:
            key = "mips" if rect[1] > res.mips else "layers"
            raise _fail(path + [key], f"range exceeds '{res.name}' ({res.mips} mips, {res.layers} layers)")

    for i, res in enumerate(resources):
        for key in ("initial", "final"):
            for k, state in enumerate(getattr(res, key) or []):
                where: list[PathPart] = ["resources", i, key] + ([] if state.index is None else [k])
                check(i, state.rect, where + ["subresource"])
    for p in passes:
        at: list[PathPart] = ["passes", p.index]
        for j, a in enumerate(p.accesses):
            check(a.resource, a.rect, at + ["accesses", j, "subresource"])
            if resources[a.resource].is_image and a.layout is None:
                raise _fail(at + ["accesses", j, "layout"], "an image access needs a layout")
        for key, blist in (("barriers", p.barriers), ("releases", p.releases)):
            for k, b in enumerate(blist):
                check(b.resource, b.rect, at + [key, k, "subresource"])
                if b.resource >= 0 and resources[b.resource].is_image:
                    for side, sc in (("src", b.src), ("dst", b.dst)):
                        if sc.layout is None:
                            raise _fail(at + [key, k, side, "layout"], "an image barrier needs layouts")

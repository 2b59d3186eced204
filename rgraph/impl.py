"""Pass implementations: the registry that a graph's ``impl:`` names resolve through.

A pass implementation is a class registered under a name::

    from rgraph.impl import PassImpl, register

    @register("tonemap_filmic")
    class Tonemap(PassImpl):
        def __init__(self, setup):          # rgraph.vk.passkit.PassSetup: pipelines, views, params
            ...
        def record(self, rec, frame_set):   # rgraph.vk.record_context.RecordContext: no barrier calls
            ...

Built-in implementations live in ``rgraph.passes`` (``passes/`` in a checkout) and
register exactly this way; a user's package registers through the ``rgraph.passes`` entry
point group (each entry point names a module to import). Nothing here imports Vulkan.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import import_module
from importlib.metadata import entry_points
from typing import Any, ClassVar, TypeVar

from rgraph.errors import quote

_REGISTRY: dict[str, type[PassImpl]] = {}
_LOADED = False
_FAILED: dict[str, Exception] = {}  # module -> why it could not be imported

T = TypeVar("T", bound="type[PassImpl]")


@dataclass(frozen=True)
class Param:
    """The declared type and range of one param an implementation reads (``param_schema``).

    ``kind`` is ``int``, ``float``, ``bool`` or ``str``; numbers lie in ``[low, high]``;
    ``choices`` (if any) lists every valid value. ``output``: the value is a file the pass
    writes, which only the user may name (``-p`` on the command line), never a graph file.
    Checked before the device opens.
    """

    kind: type = float
    low: float | None = None
    high: float | None = None
    choices: tuple[Any, ...] = ()
    output: bool = False

    def problem(self, value: Any) -> str | None:
        """Why ``value`` is not valid, or None."""
        if self.kind is bool:
            ok = isinstance(value, bool) or (isinstance(value, int | float) and value in (0, 1))
            return None if ok else f"must be true or false (or 0/1), got {_shown(value)}"
        if self.kind is str:
            if not isinstance(value, str):
                return f"must be a string, got {_shown(value)}"
        elif self.kind is int:
            if isinstance(value, bool) or not isinstance(value, int | float) or value != value // 1:
                return f"must be an integer{self._range()}, got {_shown(value)}"
        elif isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            return f"must be a finite number{self._range()}, got {_shown(value)}"
        if self.choices and value not in self.choices:
            return f"must be one of {', '.join(str(c) for c in self.choices)}, got {_shown(value)}"
        if self.low is not None and value < self.low or self.high is not None and value > self.high:
            return f"must be{self._range()}, got {_shown(value)}"
        return None

    def _range(self) -> str:
        if self.low is not None and self.high is not None:
            return f" in {self.low:g}..{self.high:g}"
        if self.low is not None:
            return f" >= {self.low:g}"
        if self.high is not None:
            return f" <= {self.high:g}"
        return ""


def _shown(value: Any) -> str:
    return quote(value)


class PassImpl:
    """Base class of pass implementations (see the module docstring).

    ``param_schema`` (name -> :class:`Param`) declares the params the implementation reads;
    :func:`param_problems` checks a plan's values against it before anything runs.

    Class attributes a raster implementation may set:

    - ``attachment_load``: resource -> ``"clear"``, ``"load"`` or ``"dont_care"`` (default:
      ``load`` for blended colour and for depth written after an earlier writer in the frame,
      ``clear`` otherwise);
    - ``clear_values``: resource -> RGBA floats (colour) or a depth float (default 0: reversed-Z far);
    - ``owns_render_pass``: True when the implementation creates its render passes itself
      (``setup.own``) and begins and ends them in ``record`` (the probe: one per layer);
      otherwise the runtime makes one from the pass's attachments and wraps ``record`` in it;
    - ``multiview``: True when the shaders handle ``gl_ViewIndex`` (``RGRAPH_VIEWS``): with the
      graph param ``views`` > 1 and attachments of that many layers, the runtime's render pass
      renders every view in one pass (VK_KHR_multiview view mask, one framebuffer layer);
      ``"layers"``: every layer of layered attachments is a view, whatever ``views`` says
      (``gl_ViewIndex`` is the layer: the sort-last composite);
    """

    attachment_load: ClassVar[dict[str, str]] = {}
    clear_values: ClassVar[dict[str, Any]] = {}
    owns_render_pass: ClassVar[bool] = False
    multiview: ClassVar[bool | str] = False
    param_schema: ClassVar[dict[str, Param]] = {}

    def __init__(self, setup: Any) -> None:
        self.setup = setup

    def record(self, rec: Any, frame_set: int) -> None:
        """Record this pass's work for frame-in-flight set ``frame_set`` (once per run)."""
        raise NotImplementedError

    def update(self, frame: int, frame_set: int) -> None:
        """Per-frame host work before the frame is submitted (mapped memory only). Optional."""

    def destroy(self) -> None:
        """Free what the implementation created itself (``setup.own`` objects are freed for it)."""


def register(name: str) -> Callable[[T], T]:
    """Class decorator: make ``cls`` the implementation named ``name``."""

    def decorate(cls: T) -> T:
        other = _REGISTRY.get(name)
        if other is not None and other is not cls and other.__qualname__ != cls.__qualname__:
            raise ValueError(f"pass implementation {name!r} is registered twice ({other.__module__} and "
                             f"{cls.__module__})")
        _REGISTRY[name] = cls
        cls.impl_name = name  # type: ignore[attr-defined]
        return cls

    return decorate


def load_implementations() -> None:
    """Import the built-in passes and every ``rgraph.passes`` entry point (once)."""
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    from rgraph.resources import builtin_passes

    _FAILED.update(builtin_passes().load_all())
    for ep in entry_points(group="rgraph.passes"):
        module = ep.value.split(":")[0]
        try:
            import_module(module)
        except Exception as exc:  # noqa: BLE001 -- reported by lookup
            _FAILED[module] = exc


def lookup(name: str) -> type[PassImpl]:
    """The implementation registered as ``name``; KeyError lists the known names."""
    load_implementations()
    try:
        return _REGISTRY[name]
    except KeyError:
        broken = "".join(f"; module {m} failed to import: {type(e).__name__}: {e}" for m, e in sorted(_FAILED.items()))
        raise KeyError(f"no pass implementation named {name!r}; known: {', '.join(sorted(_REGISTRY)) or '(none)'}"
                       f"{broken}") from None


def names() -> list[str]:
    load_implementations()
    return sorted(_REGISTRY)


def scene_param_schema() -> dict[str, Param]:
    """Graph params every implemented pass of a plan with a scene reads through its shader
    defines (``rgraph.vk.scene_modes``): refused before the device opens, located in the graph."""
    from rgraph.vk.scene_modes import MAX_VIEWS, MODES, NAIVE_WAYS

    return {"views": Param(int, 1, MAX_VIEWS), "draw.mode": Param(str, choices=MODES),
            "draw.naive": Param(str, choices=NAIVE_WAYS)}


def param_problems(plan: Mapping[str, Any], user_params: Mapping[str, Any] | None = None) -> list[tuple[str, str]]:
    """(param name, message) for every param value of ``plan`` that an implementation's
    ``param_schema`` refuses; the values a pass sees are the plan's merged with its own.
    With ``user_params`` (what the user gave on the command line), an ``output`` param set to
    anything else is refused too."""
    found: list[tuple[str, str]] = []
    seen: set[tuple[str, str]] = set()
    shared = plan.get("params") or {}
    for p in plan.get("passes", []):
        impl = p.get("impl")
        if not impl:
            continue
        try:
            cls = lookup(impl)
        except KeyError:
            continue  # the executor reports unknown implementations itself
        values = {**shared, **(p.get("params") or {})}
        schema = {**cls.param_schema, **(scene_param_schema() if plan.get("scene_source") else {})}
        for name, spec in schema.items():
            if name not in values:
                continue
            problem = spec.problem(values[name])
            if problem is None and spec.output and user_params is not None and values[name] not in ("", None):
                if str(user_params.get(name, "")) != str(values[name]):
                    problem = (f"names an output file ({quote(values[name])}) but was not given on the command "
                               f"line: files are written only where the user says (-p {name}=PATH)")
            if problem is not None and (name, problem) not in seen:
                seen.add((name, problem))
                found.append((name, f"param '{name}' (read by pass '{p.get('name')}', impl '{impl}') {problem}"))
    return found

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

from collections.abc import Callable
from importlib import import_module
from importlib.metadata import entry_points
from typing import Any, ClassVar, TypeVar

_REGISTRY: dict[str, type[PassImpl]] = {}
_LOADED = False
_FAILED: dict[str, Exception] = {}  # module -> why it could not be imported

T = TypeVar("T", bound="type[PassImpl]")


class PassImpl:
    """Base class of pass implementations (see the module docstring).

    Class attributes a raster implementation may set:

    - ``attachment_load``: resource -> ``"clear"``, ``"load"`` or ``"dont_care"`` (default:
      ``load`` for blended colour and for depth written after an earlier writer in the frame,
      ``clear`` otherwise);
    - ``clear_values``: resource -> RGBA floats (colour) or a depth float (default 0: reversed-Z far);
    - ``owns_render_pass``: True when the implementation creates its render passes itself
      (``setup.own``) and begins and ends them in ``record`` (the probe: one per layer);
      otherwise the runtime makes one from the pass's attachments and wraps ``record`` in it.
    """

    attachment_load: ClassVar[dict[str, str]] = {}
    clear_values: ClassVar[dict[str, Any]] = {}
    owns_render_pass: ClassVar[bool] = False

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

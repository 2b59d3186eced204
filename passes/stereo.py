"""The graph param ``views`` for the screen-space passes (issue 18 stereo): how many eyes (for
the compute passes checked against the layers of the images they touch), and the shader defines."""

from __future__ import annotations

from typing import Any

from rgraph.vk.errors import ExecutionError


def view_layers(setup: Any) -> int:
    """Layers a pass draws or dispatches over: the param ``views``, at least 1 (a full-screen or
    layered pass draws one instance per layer)."""
    return max(1, int(setup.param("views", 1)))


def checked_views(setup: Any, resources: tuple[str, ...]) -> int:
    """The param ``views`` (1 or 2), checking that each of ``resources`` has a layer per view."""
    views = int(setup.param("views", 1))
    if not 1 <= views <= 2:
        raise ExecutionError(f"pass {setup.name!r}: views must be 1 or 2, got {views}")
    for name in resources:
        layers = int(setup.resource_plan(name).get("layers", 1))
        if layers != views:
            raise ExecutionError(f"pass {setup.name!r}: views={views} needs {name} with a layer per view "
                                 f"(layers: \"${{params.views}}\"), it has {layers}")
    return views


def stereo_defines(views: int) -> dict[str, int]:
    """Shader defines for ``views`` (none at views=1: the mono SPIR-V is unchanged)."""
    return {"RGRAPH_VIEWS": views} if views > 1 else {}

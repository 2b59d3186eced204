"""Find the bundled data (graphs, shaders, passes) from a wheel or from a plain checkout.

In a wheel they live inside the package (``rgraph/graphs`` ...). In a checkout run with only
``PYTHONPATH`` set (the GPU machines), they are the top-level ``graphs/``, ``shaders/`` and
``passes/`` beside the ``rgraph/`` package directory.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

_PACKAGE = Path(__file__).resolve().parent


def _checkout_dir(name: str) -> Path | None:
    """``name`` beside the package when the package is a source checkout's (``pyproject.toml``
    beside it): that checkout's own data, even where an editable install maps ``rgraph.<name>``
    to another checkout (a worktree run with ``PYTHONPATH``)."""
    beside = _PACKAGE.parent / name
    return beside if (_PACKAGE.parent / "pyproject.toml").is_file() and beside.is_dir() else None


def data_dir(name: str) -> Path:
    """``graphs``, ``shaders`` or ``passes``: inside the package, else beside it."""
    inside = _PACKAGE / name
    if inside.is_dir():
        return inside
    checkout = _checkout_dir(name)
    if checkout is not None:
        return checkout
    spec = importlib.util.find_spec(f"rgraph.{name}")
    if spec and spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations)))
    return _PACKAGE.parent / name


def graphs_dir() -> Path:
    return data_dir("graphs")


def bundled_graphs() -> dict[str, Path]:
    """Bundled graph names -> paths (``rgraph run surgery``)."""
    return {p.stem: p for p in sorted(graphs_dir().glob("*.yaml"))}


def resolve_graph(arg: str) -> Path:
    """A path as given, or the bundled graph of that name."""
    path = Path(arg)
    if path.exists() or path.suffix in (".yaml", ".yml", ".json"):
        return path
    return bundled_graphs().get(arg, path)


def bundled_scenes() -> dict[str, Path]:
    """Bundled scene names -> paths (``--scene cct_no_sss``)."""
    return {p.stem: p for p in sorted((graphs_dir() / "scenes").glob("*.yaml"))}


def resolve_scene(arg: str | Path) -> Path:
    """A scene path as given, or the bundled scene of that name; a name that is neither is an error."""
    path = Path(arg)
    if path.exists() or path.suffix in (".yaml", ".yml"):
        return path
    scenes = bundled_scenes()
    if str(arg) in scenes:
        return scenes[str(arg)]
    from rgraph.errors import RGraphError

    raise RGraphError.in_file("<command line>", f"--scene {arg}: no such file or bundled scene "
                                                f"(bundled: {', '.join(scenes) or 'none'})")


def builtin_passes() -> ModuleType:
    """Import ``rgraph.passes`` (the built-in implementations), from a wheel or a checkout."""
    if "rgraph.passes" in sys.modules:
        return sys.modules["rgraph.passes"]
    checkout = _checkout_dir("passes")
    if checkout is None and importlib.util.find_spec("rgraph.passes") is not None:
        return importlib.import_module("rgraph.passes")
    init = (checkout or _PACKAGE.parent / "passes") / "__init__.py"
    spec = importlib.util.spec_from_file_location("rgraph.passes", init, submodule_search_locations=[str(init.parent)])
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    sys.modules["rgraph.passes"] = module
    spec.loader.exec_module(module)
    return module

"""Load a graph file and its includes into one :class:`GraphSource`.

Includes are resolved relative to the including file; their declarations come AFTER the
including file's own (so ``include: [post/bloom.yaml]`` appends the post chain). Duplicate
names across files, missing files and include cycles are errors at the include entry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from rgraph.errors import Location, RGraphError, quote
from rgraph.spec.models import GraphFile, Pass
from rgraph.spec.models import Resource as ResourceModel
from rgraph.spec.paths import referenced
from rgraph.spec.pydantic_errors import translate
from rgraph.spec.yaml_source import SourceMap, load_yaml

FORMAT_VERSION = 1
MAX_INCLUDE_DEPTH = 32
MAX_INCLUDED_FILES = 256


@dataclass(frozen=True)
class Located:
    """A model with the source map and path it came from, for error locations."""

    name: str
    model: Any
    smap: SourceMap
    path: tuple[str | int, ...]

    def loc(self, *sub: str | int) -> Location:
        return self.smap.value((*self.path, *sub))

    def key_loc(self, *sub: str | int) -> Location:
        return self.smap.key((*self.path, *sub))


@dataclass
class GraphSource:
    """All files of a graph merged: declaration order preserved, locations kept."""

    name: str
    path: Path
    description: str | None
    default_scene: Path | None
    default_scene_loc: Location | None = None
    memory_policy: str | None = None
    params: dict[str, Located] = field(default_factory=dict)
    resources: dict[str, Located] = field(default_factory=dict)
    passes: dict[str, Located] = field(default_factory=dict)
    outputs: list[Located] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)

    def resource(self, name: str) -> ResourceModel:
        return self.resources[name].model

    def pass_(self, name: str) -> Pass:
        return self.passes[name].model


def parse_graph_file(path: Path, display: str) -> tuple[GraphFile, SourceMap]:
    """Parse and validate one file (no includes)."""
    data, smap = load_yaml(path, display)
    if not isinstance(data, dict):
        what = "empty" if data is None else f"a {type(data).__name__.replace('list', 'list').replace('str', 'string')}"
        raise RGraphError.at(smap.value(()), f"a graph file must be a mapping with 'rgraph: 1', but this is {what}")
    version = data.get("rgraph")
    if version is None:
        raise RGraphError.at(smap.value(()), "missing required key 'rgraph' (the format version: 'rgraph: 1')")
    if version != FORMAT_VERSION or isinstance(version, bool):
        raise RGraphError.at(
            smap.value(("rgraph",)),
            f"unsupported format version {quote(version)}; this rgraph reads 'rgraph: {FORMAT_VERSION}'",
        )
    try:
        model = GraphFile.model_validate(data)
    except ValidationError as exc:
        raise translate(exc, smap, GraphFile, data) from None
    return model, smap


def load_graph(path: str | Path) -> GraphSource:
    """Load ``path`` and everything it includes (each file once, however often it is included)."""
    root = Path(path)
    model, smap = parse_graph_file(root, str(path))
    if model.memory_policy is not None:
        _check_policy(model.memory_policy, smap)
    scene = None
    if model.scene:
        scene = referenced(root.parent, root.parent, model.scene, smap.value(("scene",)), "scene file")
    source = GraphSource(
        name=model.name or root.stem,
        path=root,
        description=model.description,
        default_scene=scene,
        default_scene_loc=smap.value(("scene",)) if model.scene else None,
        memory_policy=model.memory_policy,
    )
    _merge(source, root, str(path), model, smap, chain=(root.resolve(),), seen={root.resolve()})
    return source


def _check_policy(text: str, smap: SourceMap) -> None:
    from rgraph.memory.policy import parse_policy

    try:
        parse_policy(text)
    except ValueError as exc:
        raise RGraphError.at(smap.value(("memory_policy",)), str(exc)) from None


def _merge(
    source: GraphSource, file: Path, display: str, model: GraphFile, smap: SourceMap,
    chain: tuple[Path, ...], seen: set[Path],
) -> None:
    source.files.append(file)
    for kind, table in (("params", model.params), ("resources", model.resources), ("passes", model.passes)):
        target: dict[str, Located] = getattr(source, kind)
        for name, value in table.items():
            if name in target:
                first = target[name]
                where = first.key_loc()
                raise RGraphError.at(
                    smap.key((kind, name)),
                    f"duplicate {kind[:-1].replace('passe', 'pass')} {quote(name)} (first defined at {where})",
                )
            target[name] = Located(name, value, smap, (kind, name))
    for i, name in enumerate(model.outputs):
        source.outputs.append(Located(name, name, smap, ("outputs", i)))
    for i, include in enumerate(model.include):
        loc = smap.value(("include", i))
        inc_path = referenced(file.parent, source.path.parent, include, loc, "included file")
        inc_display = str(Path(display).parent / include)
        resolved = inc_path.resolve()
        if resolved in chain:
            cycle = " -> ".join(p.name for p in (*chain, resolved))
            raise RGraphError.at(loc, f"include cycle: {cycle}")
        if resolved in seen:
            continue  # already merged (a diamond): its declarations are there once
        if len(chain) >= MAX_INCLUDE_DEPTH:
            raise RGraphError.at(loc, f"includes nested deeper than {MAX_INCLUDE_DEPTH}")
        if len(seen) >= MAX_INCLUDED_FILES:
            raise RGraphError.at(loc, f"more than {MAX_INCLUDED_FILES} included files")
        if not inc_path.is_file():
            raise RGraphError.at(loc, f"included file {quote(include)} not found (looked in {file.parent or '.'})")
        seen.add(resolved)
        try:
            inc_model, inc_smap = parse_graph_file(inc_path, inc_display)
            inc_smap.via = loc
            _merge(source, inc_path, inc_display, inc_model, inc_smap, (*chain, resolved), seen)
        except RGraphError as err:
            raise err.included_from(inc_display, loc) from None

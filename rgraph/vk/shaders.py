"""GLSL -> SPIR-V with ``glslc``, cached by content hash, plus finding bundled shaders.

``compile_shader("blur.comp", defines={"TAPS": 9})`` runs ``glslc`` (Vulkan 1.3 target,
SPIR-V 1.6, ``-O -g`` so variable names survive for reflection) and returns the SPIR-V
bytes with their reflection. This module is pure: it never imports ``vulkan``.

The cache works like ccache's direct mode, in two steps:

1. ``<key1>.json`` where key1 = hash(cache format, ``glslc --version``, flags, defines,
   stage, the source's absolute path and bytes). It lists every file glslc read
   (from its ``-MD -MF`` depfile) and is written after each compile.
2. ``<key2>.spv`` where key2 = hash(key1, each listed file's path and current bytes).

A lookup re-hashes the listed files, so editing an included header changes key2 and
recompiles; an unchanged shader is served without running glslc. The directory is
``$RGRAPH_CACHE/spirv`` or ``$XDG_CACHE_HOME/rgraph/spirv`` (default
``~/.cache/rgraph/spirv``). A read-only or missing-and-uncreatable directory still serves
hits and otherwise compiles to memory. Known gap (as in ccache): a new header that would
shadow an already-resolved ``#include`` in an earlier include directory is not noticed.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import shutil
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from rgraph.errors import Diagnostic, Location, RGraphError
from rgraph.vk.spirv_reflect import Reflection, reflect

__all__ = [
    "STAGE_OF_EXTENSION", "CompiledShader", "cache_dir", "compile_shader", "find_shader", "shader_dirs",
]

TARGET_ENV = "vulkan1.3"  # SPIR-V 1.6; lavapipe (Vulkan 1.4) and the 1.3.239 validation layer take it
CACHE_FORMAT = 1  # bump when the cache layout or the meaning of a key changes
STAGE_OF_EXTENSION: dict[str, str] = {
    ext: ext for ext in ("vert", "tesc", "tese", "geom", "frag", "comp", "rgen", "rmiss", "rchit",
                         "rahit", "rint", "rcall", "mesh", "task")
}
_INSTALL_HINT = "install it with `apt-get install glslc` (Debian/Ubuntu) or from the Vulkan SDK"
_DEFINE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# "file:line: error: msg" or "file:line:col: error: msg" or "file: error: msg"
_DIAGNOSTIC = re.compile(
    r"^(?P<file>.+?):(?:(?P<line>\d+):(?:(?P<col>\d+):)?)? (?P<severity>error|warning): (?P<message>.*)$")
_QUOTED_TOKEN = re.compile(r"^'([^']+)'")


@dataclass(frozen=True)
class CompiledShader:
    """SPIR-V for one GLSL file and one set of defines. ``key`` is the cache content hash."""

    path: Path
    stage: str
    spirv: bytes = field(repr=False)
    defines: tuple[tuple[str, str], ...]
    reflection: Reflection = field(repr=False)
    key: str = ""


# ----------------------------------------------------------------------------- locations


def shader_dirs() -> list[Path]:
    """Directories searched for shaders: ``$RGRAPH_SHADER_PATH`` entries, then the bundled dir.

    The bundled dir is the ``rgraph.shaders`` package (a wheel, or an editable install that
    maps it to ``shaders/``), else ``shaders/`` beside the ``rgraph/`` package directory
    (a plain checkout on ``PYTHONPATH``).
    """
    dirs = [Path(p) for p in os.environ.get("RGRAPH_SHADER_PATH", "").split(os.pathsep) if p]
    bundled = _bundled_shader_dir()
    if bundled is not None:
        dirs.append(bundled)
    unique: list[Path] = []
    for d in dirs:
        d = d.resolve()
        if d.is_dir() and d not in unique:
            unique.append(d)
    return unique


def _bundled_shader_dir() -> Path | None:
    """``rgraph.resources.data_dir("shaders")``: the package's, a checkout's own ``shaders/``
    (even where an editable install maps ``rgraph.shaders`` to another checkout), else the mapped one."""
    from rgraph.resources import data_dir

    bundled = data_dir("shaders")
    return bundled if bundled.is_dir() else None


def find_shader(name: str) -> Path:
    """The first file called ``name`` (e.g. ``"common/probe.comp"``) in ``shader_dirs()``."""
    candidate = Path(name)
    if candidate.is_absolute():
        if candidate.is_file():
            return candidate
        raise RGraphError.in_file(candidate, "shader file not found")
    dirs = shader_dirs()
    for d in dirs:
        if (d / candidate).is_file():
            return d / candidate
    searched = ", ".join(str(d) for d in dirs) or "(no shader directories)"
    raise RGraphError.in_file(name, f"shader {name!r} not found in {searched}")


def cache_dir() -> Path:
    """Where compiled SPIR-V is cached (see the module docstring)."""
    root = os.environ.get("RGRAPH_CACHE")
    if root:
        return Path(root).expanduser() / "spirv"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "rgraph" / "spirv"


def stage_of(path: Path) -> str | None:
    """The stage a file name implies: ``x.comp`` or ``x.comp.glsl``; None for plain ``.glsl``."""
    suffixes = [s.lstrip(".") for s in path.suffixes]
    if suffixes and suffixes[-1] == "glsl":
        suffixes.pop()
    return STAGE_OF_EXTENSION.get(suffixes[-1]) if suffixes else None


# ----------------------------------------------------------------------------- glslc


def glslc_path() -> str | None:
    """``$RGRAPH_GLSLC`` or ``glslc`` on PATH."""
    return os.environ.get("RGRAPH_GLSLC") or shutil.which("glslc")


def run_glslc(args: Sequence[str], cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run glslc (the one place that does; unit tests count calls here)."""
    return subprocess.run(list(args), cwd=cwd, capture_output=True, text=True, check=False)


@lru_cache(maxsize=8)
def _glslc_version(glslc: str) -> str:
    result = run_glslc([glslc, "--version"])
    if result.returncode != 0:
        raise RGraphError.in_file(glslc, f"`glslc --version` failed: {result.stderr.strip()}")
    return result.stdout.strip()


def _require_glslc(source: Path) -> str:
    glslc = glslc_path()
    if glslc is None or not (os.path.isfile(glslc) and os.access(glslc, os.X_OK)):
        raise RGraphError.in_file(source, f"glslc (the GLSL to SPIR-V compiler) not found: {_INSTALL_HINT}")
    return glslc


def _define_value(name: str, value: object, source: Path) -> str:
    if not _DEFINE_NAME.match(name):
        raise RGraphError.in_file(source, f"bad macro name {name!r} in shader defines")
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        if not math.isfinite(value):
            raise RGraphError.in_file(source, f"define {name}={value} is not a finite number")
        return repr(value)
    text = str(value)
    if "\n" in text:
        raise RGraphError.in_file(source, f"define {name} has a newline in its value")
    return text


def _parse_depfile(text: str, cwd: Path) -> list[Path]:
    """Prerequisites of a make rule ``target: dep dep \\<newline> dep`` (spaces escaped ``\\ ``)."""
    body = text.replace("\\\n", " ")
    _, _, deps = body.partition(": ")
    tokens = re.findall(r"(?:\\.|[^\s\\])+", deps)
    return [(cwd / re.sub(r"\\(.)", r"\1", tok)).resolve() for tok in tokens]


def _diagnostics(stderr: str, source: Path, defines: tuple[tuple[str, str], ...]) -> list[Diagnostic]:
    """glslc's ``file:line: error: message`` lines as diagnostics (warnings dropped)."""
    suffix = f" (defines: {' '.join(f'{k}={v}' for k, v in defines)})" if defines else ""
    found: list[Diagnostic] = []
    last_file = None
    for raw in stderr.splitlines():
        match = _DIAGNOSTIC.match(raw)
        if match is None:
            # continuation of the previous error ("file: GL_EXT_mesh_shader")
            if found and last_file and raw.startswith(f"{last_file}: "):
                prev = found[-1]
                found[-1] = Diagnostic(prev.location, f"{prev.message.removesuffix(suffix)}"
                                       f" {raw[len(last_file) + 2:].strip()}{suffix}")
            continue
        if match["severity"] != "error":
            last_file = None
            continue
        file = match["file"]
        last_file = file
        if file == "glslc":
            file = str(source)
        line = int(match["line"] or 1)
        message = re.sub(r"\s+", " ", match["message"]).strip()
        col = int(match["col"]) if match["col"] else _guess_column(file, line, message)
        found.append(Diagnostic(Location(file, line, col), f"GLSL: {message}{suffix}"))
    if not found:
        text = stderr.strip() or "glslc failed without a message"
        found.append(Diagnostic(Location(str(source), 1, 1), f"GLSL: {text}{suffix}"))
    return found


def _guess_column(file: str, line: int, message: str) -> int:
    """glslc gives no column: point at the quoted token (``'foo' : undeclared``) if on the line."""
    token = _QUOTED_TOKEN.match(message)
    if token is None:
        return 1
    try:
        text = Path(file).read_text(errors="replace").splitlines()[line - 1]
    except (OSError, IndexError):
        return 1
    found = re.search(rf"(?<![A-Za-z0-9_]){re.escape(token[1])}(?![A-Za-z0-9_])", text)
    return found.start() + 1 if found else 1


# ----------------------------------------------------------------------------- cache


def _sha(*parts: bytes | str) -> str:
    h = hashlib.sha256()
    for part in parts:
        data = part.encode() if isinstance(part, str) else part
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()


def _deps_key(key1: str, deps: Sequence[str]) -> str:
    parts: list[bytes | str] = [key1]
    for dep in deps:
        try:
            content = Path(dep).read_bytes()
        except OSError:
            content = b"\0missing"
        parts += [dep, hashlib.sha256(content).hexdigest()]
    return _sha(*parts)


def _write_atomic(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def _lookup(directory: Path, key1: str) -> tuple[str, bytes] | None:
    try:
        manifest = json.loads((directory / f"{key1}.json").read_text())
        key2 = _deps_key(key1, manifest["deps"])
        spirv = (directory / f"{key2}.spv").read_bytes()
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if len(spirv) < 20 or spirv[:4] != b"\x03\x02\x23\x07":
        return None  # truncated or foreign file: recompile
    return key2, spirv


def _store(directory: Path, key1: str, key2: str, deps: Sequence[str], spirv: bytes) -> None:
    try:
        _write_atomic(directory / f"{key2}.spv", spirv)
        _write_atomic(directory / f"{key1}.json", json.dumps({"deps": list(deps)}, indent=1).encode())
    except OSError:
        pass  # read-only cache: the result lives in memory only


# ----------------------------------------------------------------------------- compile


def compile_shader(
    path: Path | str,
    *,
    defines: Mapping[str, object] = {},  # noqa: B006 -- read-only default
    include_dirs: Sequence[Path | str] = (),
    stage: str | None = None,
    optimize: bool = True,
    cache: Path | str | None = None,
) -> CompiledShader:
    """Compile one GLSL file to SPIR-V (or fetch it from the cache) and reflect it.

    ``defines`` become ``-DNAME=VALUE`` (bools as 1/0); ``include_dirs`` are searched after
    the file's own directory, then ``shader_dirs()``. ``stage`` defaults to the extension.
    ``cache`` overrides ``cache_dir()``. Raises ``RGraphError`` at glslc's ``file:line``.
    """
    source = Path(path).expanduser().resolve()
    if not source.is_file():
        raise RGraphError.in_file(path, "shader file not found")
    stage = stage or stage_of(source)
    if stage not in STAGE_OF_EXTENSION:
        raise RGraphError.in_file(source, f"unknown shader stage {stage!r}: use an extension like .comp or "
                                          f"pass stage= one of {sorted(STAGE_OF_EXTENSION)}")
    define_items = tuple(sorted((name, _define_value(name, value, source)) for name, value in defines.items()))
    search = []
    for d in [source.parent, *(Path(i).expanduser().resolve() for i in include_dirs), *shader_dirs()]:
        if d not in search:
            search.append(d)
    flags = [f"--target-env={TARGET_ENV}", "-O" if optimize else "-O0", "-g", f"-fshader-stage={stage}",
             *(f"-I{d}" for d in search),
             *(f"-D{name}={value}" if value != "" else f"-D{name}" for name, value in define_items)]
    glslc = _require_glslc(source)
    text = source.read_bytes()
    key1 = _sha(f"rgraph-spirv-{CACHE_FORMAT}", _glslc_version(glslc), *flags, str(source), text)
    directory = Path(cache).expanduser() if cache is not None else cache_dir()

    hit = _lookup(directory, key1)
    if hit is not None:
        key2, spirv = hit
    else:
        spirv, deps = _compile(glslc, flags, source, define_items)
        key2 = _deps_key(key1, deps)
        if source.read_bytes() == text:  # not edited while glslc ran
            _store(directory, key1, key2, deps, spirv)
    return CompiledShader(path=source, stage=stage, spirv=spirv, defines=define_items,
                          reflection=reflect(spirv), key=key2)


def _compile(glslc: str, flags: list[str], source: Path,
             defines: tuple[tuple[str, str], ...]) -> tuple[bytes, list[str]]:
    with tempfile.TemporaryDirectory(prefix="rgraph-glslc-") as tmp:
        out, depfile = Path(tmp) / "out.spv", Path(tmp) / "out.d"
        result = run_glslc([glslc, *flags, "-MD", "-MF", str(depfile), "-o", str(out), str(source)],
                           cwd=source.parent)
        if result.returncode != 0:
            raise RGraphError(_diagnostics(result.stderr, source, defines))
        spirv = out.read_bytes()
        deps = _parse_depfile(depfile.read_text(), source.parent) if depfile.exists() else [source]
    unique = sorted({str(d) for d in deps} | {str(source)})
    return spirv, unique

"""Native accelerators: every ``rgraph/**/*.pyx`` is compiled by Cython into an extension module
beside it. Each one is optional: when it cannot be built (no compiler, no Cython) the install
still succeeds and rgraph runs the pure-Python module that the extension mirrors, with the same
results (``rgraph.native``). A module in ``TWINS`` is compiled as it is, under its twin's name,
typed by the twin's ``.pxd`` (Cython's augmenting declarations); the module itself stays the
pure-Python fallback and the reference. Everything else is declared in pyproject.toml."""

from pathlib import Path

from setuptools import Extension, setup

#: Pure-Python modules -> the extension module compiled from the same source (typed by the
#: ``.pxd`` of the extension's name beside it).
#: scripts/setup.sh rebuilds when one of these changes: add a new twin there too.
TWINS = {"rgraph/compiler/sync.py": "rgraph.compiler._sync"}


def native_extensions() -> list[Extension]:
    sources = sorted(Path("rgraph").rglob("*.pyx"))
    if not sources and not TWINS:
        return []
    try:
        from Cython.Build import cythonize
    except ImportError:
        return []
    exts = [Extension(".".join(p.with_suffix("").parts), [str(p)], optional=True) for p in sources]
    twins = [Extension(name, [source], optional=True) for source, name in TWINS.items()]
    # a twin keeps Python's semantics (negative indices, IndexError); its types come from its .pxd,
    # not from its annotations (written for readers)
    return (cythonize(exts, language_level=3, quiet=True,
                      compiler_directives={"boundscheck": False, "wraparound": False, "cdivision": True})
            + cythonize(twins, language_level=3, quiet=True, compiler_directives={"annotation_typing": False}))


setup(ext_modules=native_extensions())

"""Native accelerators: every ``rgraph/**/*.pyx`` is compiled by Cython into an extension module
beside it. Each one is optional: when it cannot be built (no compiler, no Cython) the install
still succeeds and rgraph runs the pure-Python module that the extension mirrors, with the same
results (``rgraph.native``). Everything else is declared in pyproject.toml."""

from pathlib import Path

from setuptools import Extension, setup


def native_extensions() -> list[Extension]:
    sources = sorted(Path("rgraph").rglob("*.pyx"))
    if not sources:
        return []
    try:
        from Cython.Build import cythonize
    except ImportError:
        return []
    exts = [Extension(".".join(p.with_suffix("").parts), [str(p)], optional=True) for p in sources]
    return cythonize(exts, language_level=3, quiet=True,
                     compiler_directives={"boundscheck": False, "wraparound": False, "cdivision": True})


setup(ext_modules=native_extensions())

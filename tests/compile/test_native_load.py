"""``rgraph.native``: a build older than its ``.pyx`` is not used (the Python code runs), and
``RGRAPH_NATIVE=0`` turns every accelerator off."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from rgraph import native


def test_a_build_older_than_its_source_is_stale(tmp_path: Path) -> None:
    source = tmp_path / "_walk.pyx"
    built = tmp_path / "_walk.cpython-311-x86_64-linux-gnu.so"
    source.write_text("")
    built.write_text("")
    os.utime(source, (100, 100))
    os.utime(built, (200, 200))
    assert not native.stale(built)
    os.utime(source, (300, 300))
    assert native.stale(built)
    source.unlink()
    assert not native.stale(built)  # no source beside it (an installed wheel)


def test_a_twin_is_stale_when_its_module_changed(tmp_path: Path) -> None:
    module, types = tmp_path / "walk.py", tmp_path / "_walk.pxd"
    built = tmp_path / "_walk.cpython-311-x86_64-linux-gnu.so"
    for f, t in ((module, 300), (types, 100), (built, 200)):
        f.write_text("")
        os.utime(f, (t, t))
    assert native.stale(built)
    os.utime(module, (150, 150))
    assert not native.stale(built)


def test_a_stale_build_is_not_loaded(monkeypatch: pytest.MonkeyPatch) -> None:
    if native.load("rgraph.memory._dive") is None:
        pytest.skip("rgraph.memory._dive not built")
    monkeypatch.setattr(native, "stale", lambda built: True)
    with pytest.warns(RuntimeWarning, match="older than its .pyx"):
        assert native.load("rgraph.memory._dive") is None


def test_native_off(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RGRAPH_NATIVE", "0")
    assert native.load("rgraph.memory._dive") is None
    assert native.load("rgraph.no_such_module") is None

"""MiniMalloc trace reading, the ``rgraph place`` command and the timeline drawing."""

from __future__ import annotations

from pathlib import Path

import pytest
from locations import ROOT

from rgraph.cli import main
from rgraph.errors import RGraphError
from rgraph.memory import place
from rgraph.memory.trace import read_trace

EXAMPLE = "id,lower,upper,size\nb1,0,3,4\nb2,3,9,4\nb3,0,9,4\nb4,9,21,4\nb5,0,21,4\n"


def write(tmp_path: Path, text: str, name: str = "t.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_reads_upper_as_exclusive(tmp_path):
    blocks = read_trace(write(tmp_path, EXAMPLE))
    assert [(b.name, b.start, b.end, b.size, b.alignment) for b in blocks][:2] == [
        ("b1", 0, 2, 4, 1),
        ("b2", 3, 8, 4, 1),
    ]


def test_minimalloc_example_fits_its_capacity(tmp_path):
    placement = place(read_trace(write(tmp_path, EXAMPLE)), "optimal")
    assert placement.stats.peak_bytes == placement.stats.lower_bound_bytes == 12


def test_alignment_column(tmp_path):
    blocks = read_trace(write(tmp_path, "id,lower,upper,size,alignment\na,0,2,10,8\n"))
    assert blocks[0].alignment == 8


@pytest.mark.parametrize(
    ("text", "line", "col", "message"),
    [
        ("", 1, 1, "empty trace"),
        ("id,lower,size\n", 1, 1, "upper"),
        ("id,lower,upper,size\na,0,2\n", 2, 1, "columns"),
        ("id,lower,upper,size\na,0,2,ten\n", 2, 7, "size must be an integer"),
        ("id,lower,upper,size\na,5,2,1\n", 2, 5, "greater than lower"),
        ("id,lower,upper,size\na,0,2,1\na,1,2,1\n", 3, 1, "duplicate id"),
        ("id,lower,upper,size\na,-1,2,1\n", 2, 3, ">= 0"),
    ],
)
def test_bad_traces_point_at_the_cell(tmp_path, text, line, col, message):
    path = write(tmp_path, text)
    with pytest.raises(RGraphError) as info:
        read_trace(path)
    where = info.value.first.location
    assert (where.file, where.line, where.col) == (str(path), line, col)
    assert message in info.value.first.message


def test_place_command_prints_figures(tmp_path, capsys):
    assert main(["place", str(write(tmp_path, EXAMPLE)), "--policy", "optimal", "--verify"]) == 0
    out = capsys.readouterr().out
    assert "peak=12 lower_bound=12 ratio=1.0000" in out
    assert "verified" in out


def test_place_command_exits_2_on_bad_input(tmp_path, capsys):
    assert main(["place", str(write(tmp_path, "id,lower,upper,size\na,0,x,1\n"))]) == 2
    assert ":2:5: error:" in capsys.readouterr().err
    assert main(["place", str(write(tmp_path, EXAMPLE)), "--policy", "blocks:3MiB"]) == 2
    assert "4MiB" in capsys.readouterr().err
    assert main(["place", str(tmp_path / "missing.csv")]) == 2


def test_shared_minimalloc_traces_place_soundly():
    from rgraph.memory.verify import overlaps

    shared = ROOT.parent / "shared/data/minimalloc"
    traces = sorted(shared.glob("*.csv"))
    if not traces:
        pytest.skip("shared MiniMalloc traces not present")
    blocks = read_trace(traces[0])
    for policy in ("aliased", "tlsf", "blocks:4MiB"):
        placement = place(blocks, policy)
        assert overlaps(blocks, placement) == []
        assert placement.stats.peak_bytes >= placement.stats.lower_bound_bytes == 1048576


def test_timeline_png(tmp_path):
    from rgraph.memory.random_instances import random_blocks
    from rgraph.memory.timeline import draw_timeline

    blocks = random_blocks(20, 3)
    path = draw_timeline(blocks, place(blocks), tmp_path / "t.png", "random")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

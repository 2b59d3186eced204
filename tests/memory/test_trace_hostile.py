"""Hostile traces and budgets for ``rgraph place``: located errors, bounded time."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from rgraph.cli import main
from rgraph.memory import place
from rgraph.memory.aliased import overlapping_pairs, too_dense
from rgraph.memory.model import Block

HEAD = "id,lower,upper,size\n"


@pytest.mark.parametrize("body,where,message", [
    (HEAD + f"a,0,2,{2**200}\n", (2, 7), "size out of range (61 digits"),
    (HEAD + f"a,0,{2**63},5\n", (2, 5), "upper must be at most 2**62"),
    (HEAD + "x" * 1_000_000 + ",0,2,5\n", (2, 1), "malformed CSV line: field larger than field limit"),
    (HEAD + "x" * 2000 + ",0,2,5\n", (2, 1), "id of 2,000 characters"),
])
def test_bad_trace(tmp_path: Path, capsys, body, where, message) -> None:
    path = tmp_path / "t.csv"
    path.write_text(body)
    assert main(["place", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{path}:{where[0]}:{where[1]}: error: ") and message in err, err[:300]


@pytest.mark.parametrize("budget", ["inf", "nan", "-1", "1e9"])
def test_bad_budget(tmp_path: Path, capsys, budget: str) -> None:
    path = tmp_path / "t.csv"
    path.write_text(HEAD + "a,0,2,5\n")
    assert main(["place", str(path), "--budget", budget]) == 2
    assert "--budget must be in (0, 3600] seconds" in capsys.readouterr().err


def test_trace_must_be_a_regular_file(capsys) -> None:
    assert main(["place", "/dev/zero"]) == 2
    assert "/dev/zero:1:1: error: is not a regular file" in capsys.readouterr().err


def test_overlapping_pairs_counts_ordered_pairs() -> None:
    blocks = [Block("a", 0, 4, 1, 1, "c"), Block("b", 2, 6, 1, 1, "c"), Block("c", 5, 9, 1, 1, "c"), Block("d", 20, 21, 1, 1, "c")]
    assert overlapping_pairs(blocks) == 4  # a-b, b-c, both ways


def test_dense_lifetimes_are_placed_within_the_budget() -> None:
    """10,000 blocks alive at once (10**8 pairs): placed online in n log n, at the lower bound."""
    blocks = [Block(f"b{i}", 0, 10, 1000 + i, 1, "c") for i in range(10_000)]
    assert too_dense(blocks, 1.0)
    began = time.perf_counter()
    placement = place(blocks, "aliased", time_budget_s=1.0)
    assert time.perf_counter() - began < 10
    assert placement.stats.peak_bytes == placement.stats.lower_bound_bytes

"""A view's table as plain data, rendered to the terminal (rich) or to HTML by others."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import TextIO

from rich import box
from rich.console import Console
from rich.table import Table
from rich.text import Text

# SIMPLE_HEAD with an ASCII rule, for plain (non-terminal) output.
ASCII_SIMPLE_HEAD = box.Box("    \n    \n -- \n    \n    \n    \n    \n    \n", ascii=True)

# Width used when the output is not a terminal, so text output is the same everywhere.
PLAIN_WIDTH = 200


@dataclass(frozen=True)
class TableData:
    """A titled table of strings; ``right`` names the right-aligned (numeric) columns."""

    title: str
    columns: tuple[str, ...]
    rows: list[tuple[str, ...]] = field(default_factory=list)
    right: frozenset[str] = frozenset()
    empty: str = "(none)"


def make_console(file: TextIO | None = None, width: int | None = None) -> Console:
    """A console for ``file``: colors on a terminal; fixed width, no color and no markup otherwise."""
    file = file if file is not None else sys.stdout
    isatty = getattr(file, "isatty", None)
    if isatty is not None and isatty() and width is None:
        return Console(file=file, highlight=False, markup=False, emoji=False)
    return Console(
        file=file,
        width=width or PLAIN_WIDTH,
        color_system=None,
        force_terminal=False,
        force_jupyter=False,
        force_interactive=False,
        no_color=True,
        highlight=False,
        markup=False,
        emoji=False,
        legacy_windows=False,
        soft_wrap=False,
    )


def to_rich(data: TableData, ascii_only: bool = False) -> Table:
    """A rich table with a simple box (one header rule), cells taken literally."""
    table = Table(title=None, box=ASCII_SIMPLE_HEAD if ascii_only else box.SIMPLE_HEAD, show_edge=False, pad_edge=False, expand=False)
    for col in data.columns:
        table.add_column(col, justify="right" if col in data.right else "left", overflow="fold")
    for row in data.rows:
        table.add_row(*(Text(cell) for cell in row))
    return table


def print_table(console: Console, data: TableData) -> None:
    """The title line, then the table (or the ``empty`` note when it has no rows)."""
    console.print(Text(data.title, style="bold"))
    if not data.rows:
        console.print(Text(f"  {data.empty}"))
    elif console.is_terminal:
        console.print(to_rich(data))
    else:  # plain text: drop the padding rich adds after the last column
        with console.capture() as captured:
            console.print(to_rich(data, ascii_only=True))
        print_lines(console, [line.rstrip() for line in captured.get().splitlines()])
    console.print()


def print_lines(console: Console, lines: list[str]) -> None:
    """Lines printed as they are: never wrapped, never interpreted as markup."""
    for line in lines:
        console.print(Text(line), soft_wrap=True)

"""``rgraph --help`` imports no command module; the help table matches each command's parser."""

from __future__ import annotations

import subprocess
import sys

from rgraph.cli import build_parser
from rgraph.commands import COMMAND_HELP, COMMAND_MODULES


def _helps(parser) -> dict[str, str]:
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return {ch.dest: ch.help for ch in sub._choices_actions}


def test_help_table_matches_every_command_module() -> None:
    full = _helps(build_parser())
    assert full == COMMAND_HELP
    assert set(full) == {m.replace("_", "-") for m in COMMAND_MODULES}


def _run_main(argv: list[str]) -> list[str]:
    """stdout lines of ``rgraph.cli.main(argv)`` in a fresh interpreter, then the imported
    ``rgraph.commands.*`` modules as the last line."""
    code = ("import sys; from rgraph.cli import main\n"
            f"try:\n    main({argv!r})\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.startswith('rgraph.commands.')))")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.splitlines()


def test_top_level_help_imports_no_command_module() -> None:
    lines = _run_main(["--help"])
    assert lines[-1] == "[]"
    assert any("compile a graph into a plan JSON" in line for line in lines)


def test_a_command_imports_only_its_own_module() -> None:
    assert _run_main(["graphs"])[-1] == "['rgraph.commands.graphs']"

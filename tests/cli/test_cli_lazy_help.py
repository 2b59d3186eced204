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


def test_top_level_help_imports_no_command_module() -> None:
    code = ("import sys; from rgraph.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.startswith('rgraph.commands.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"
    assert "compile a graph into a plan JSON" in out


def test_a_command_imports_only_its_own_module() -> None:
    code = ("import sys; from rgraph.cli import main\n"
            "main(['graphs'])\n"
            "print(sorted(m for m in sys.modules if m.startswith('rgraph.commands.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "['rgraph.commands.graphs']"

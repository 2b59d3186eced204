"""The ``rgraph`` command line: dispatches to ``rgraph.commands.<name>``.

Bad input (``RGraphError``) prints ``FILE:LINE:COL: error: message`` lines and exits 2,
never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from rgraph.commands import COMMAND_MODULES
from rgraph.errors import RGraphError


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse default exits 2 too; keep its usage line
        self.print_usage(sys.stderr)
        print(f"rgraph: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="rgraph", description="A declarative render-graph compiler for Vulkan.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"rgraph.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"rgraph.commands.{name}":
                continue  # command not built yet
            raise
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    from rgraph.spec.paths import allow_outside

    args = build_parser().parse_args(argv)
    try:
        with allow_outside(bool(getattr(args, "allow_include_outside", False))):
            return int(args.func(args) or 0)
    except RGraphError as err:
        for diagnostic in err.diagnostics:
            print(diagnostic, file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        return 130

"""The ``rgraph`` command line: dispatches to ``rgraph.commands.<name>``.

Bad input (``RGraphError``) prints ``FILE:LINE:COL: error: message`` lines and exits 2,
never a traceback. An unknown option prints the usage of the subcommand it was given to.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from rgraph import __version__
from rgraph.commands import COMMAND_HELP, COMMAND_MODULES
from rgraph.errors import RGraphError


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse default exits 2 too; keep its usage line
        self.print_usage(sys.stderr)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """Every command's parser; with ``only`` (a command name), only that command's module is
    imported and the others get a stub parser with their help line (fast ``--help``)."""
    parser = _Parser(prog="rgraph", description="A declarative render-graph compiler for Vulkan.")
    parser.add_argument("--version", action="version", version=f"rgraph {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")
    for name in COMMAND_MODULES:
        command = name.replace("_", "-")
        if only is not None and command != only:
            sub.add_parser(command, help=COMMAND_HELP[command])
            continue
        try:
            module = importlib.import_module(f"rgraph.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"rgraph.commands.{name}":
                continue  # command not built yet
            raise
        module.register(sub)
    for action in sub._choices_actions:  # every command's own --help gets a description
        command = sub.choices[action.dest]
        if command.description is None:
            command.description = action.help[:1].upper() + action.help[1:] + "." if action.help else None
    return parser


def subcommand_parser(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser | None:
    """The parser of subcommand ``name`` (None when there is no such command)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices.get(name)
    return None


def main(argv: Sequence[str] | None = None) -> int:
    from rgraph.spec.paths import allow_outside

    argv = list(sys.argv[1:] if argv is None else argv)
    command = next((a for a in argv if not a.startswith("-")), "")
    parser = build_parser(only=command)
    args, extra = parser.parse_known_args(argv)
    if extra:
        (subcommand_parser(parser, args.command) or parser).error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        with allow_outside(bool(getattr(args, "allow_include_outside", False))):
            return int(args.func(args) or 0)
    except RGraphError as err:
        if getattr(args, "json", None) is True:  # --json: the diagnostics as a document on stdout
            from rgraph.commands.jsonout import document, emit, error_objects

            emit(document(args.command, False, error_objects(err.diagnostics)))
            return 2
        for diagnostic in err.diagnostics:
            print(diagnostic, file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        return 130

"""The headless `bridgefield` subcommands (no Qt, no pyvista).

Each subcommand is a module of this package with ``NAME``, ``HELP``, ``add_arguments(parser)``
and ``run(args) -> int``; they are found automatically (``COMMANDS``). The console script (viewer/cli.py) adds the
commands that draw (``shot`` and opening the explorer).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from types import ModuleType

ORDER = ("info", "demos", "bridges", "repair", "hybrid", "frep", "warmup")  # listing order in --help


def _discover() -> tuple[str, ...]:
    """Every module of this package that defines a subcommand (has NAME and run)."""
    import pkgutil
    from pathlib import Path

    names = [m.name for m in pkgutil.iter_modules([str(Path(__file__).parent)]) if m.name not in ("common",)]
    return tuple(sorted(names, key=lambda n: (ORDER.index(n) if n in ORDER else len(ORDER), n)))


COMMANDS = _discover()


def command_modules() -> list[ModuleType]:
    return [importlib.import_module(f"{__name__}.{name}") for name in COMMANDS]


def build_parser(extra: Sequence[ModuleType] = ()) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bridgefield",
        description="Repair incomplete triangulations with force lines, mesh hybrid surfaces, "
                    "triangulate F-rep objects. Without a command, opens the explorer.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod in [*command_modules(), *extra]:
        p = sub.add_parser(mod.NAME, help=mod.HELP, description=mod.HELP)
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


def run_command(args: argparse.Namespace) -> int:
    """Run a parsed command; known failures become one line on stderr and exit code 2."""
    from ..demos import UnknownDemoError
    from ..io import InputError, OutputExistsError
    from ..mesh import MeshError

    try:
        return int(args._run(args) or 0)
    except (InputError, OutputExistsError, MeshError, UnknownDemoError, ValueError) as exc:
        print(f"bridgefield {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"bridgefield {args.command}: interrupted", file=sys.stderr)
        return 130


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not args.command:
        parser.print_help()
        return 0
    return run_command(args)

"""The `bridgefield` console script.

Headless subcommands come from :mod:`algorithms.cli` and never import Qt. This module adds the
commands that draw: ``shot`` (an off-screen render) and, with no command, the explorer window.
Without a display the explorer says so and writes an off-screen render instead.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

from algorithms.cli import build_parser, run_command

DEFAULT_DEMO = "two-caps"


def has_display() -> bool:
    if sys.platform.startswith(("win", "darwin")):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def free_name(stem: str, suffix: str = ".png") -> Path:
    """A file name in the working folder that does not exist yet (never overwrite)."""
    p = Path(f"{stem}{suffix}")
    k = 1
    while p.exists():
        p = Path(f"{stem}-{k}{suffix}")
        k += 1
    return p


def _viewer_commands() -> list[ModuleType]:
    from . import shot_command

    return [shot_command]


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(extra=_viewer_commands())
    commands = set(parser._subparsers._group_actions[0].choices)  # type: ignore[union-attr]
    if argv and (argv[0] in commands or argv[0] in ("-h", "--help")):
        args = parser.parse_args(argv)
        return run_command(args)
    # no command: open the explorer (optionally on FILE or --demo NAME)
    ep = argparse.ArgumentParser(prog="bridgefield", parents=[], add_help=False)
    ep.add_argument("input", nargs="?")
    ep.add_argument("--demo")
    ep.add_argument("--points")
    ns, rest = ep.parse_known_args(argv)
    if rest:
        parser.error(f"unknown arguments: {' '.join(rest)}")
    if not has_display():
        out = free_name("bridgefield-demo")
        print("bridgefield: no display found (DISPLAY is not set): the explorer cannot open a window here.\n"
              f"Rendering the scene off screen to {out} instead.", file=sys.stderr)
        shot_args = ["shot", "-o", str(out)]
        if ns.input:
            shot_args.insert(1, ns.input)
        else:
            shot_args += ["--demo", ns.demo or DEFAULT_DEMO]
        if ns.points:
            shot_args += ["--points", ns.points]
        return run_command(parser.parse_args(shot_args))
    from .app import run_app

    return run_app(path=ns.input, demo=ns.demo or (None if ns.input else DEFAULT_DEMO), points=ns.points)


if __name__ == "__main__":
    sys.exit(main())

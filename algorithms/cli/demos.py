"""`bridgefield demos`: the bundled assets, one line each."""

from __future__ import annotations

import argparse

from ..demos import all_demos

NAME = "demos"
HELP = "list the bundled demo assets"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--kind", choices=("repair", "hybrid", "frep"), help="only demos of this kind")


def run(args: argparse.Namespace) -> int:
    demos = [d for d in all_demos().values() if args.kind is None or d.kind == args.kind]
    width = max((len(d.name) for d in demos), default=0)
    for d in demos:
        print(f"{d.name:<{width}}  {d.kind:<6}  {d.description}")
    return 0

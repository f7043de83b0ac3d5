"""Arguments and helpers shared by the subcommands."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from ..demos import demo
from ..io import InputError, OutputExistsError, load_model
from ..mesh import Icadm


def add_input(parser: argparse.ArgumentParser, *, points: bool = True, kind: str = "repair") -> None:
    """FILE or --demo NAME (and --points CLOUD for repair inputs)."""
    parser.add_argument("input", nargs="?", metavar="FILE", help="input file")
    parser.add_argument("--demo", metavar="NAME", help=f"use a bundled {kind} demo instead of FILE "
                                                       "(see `bridgefield demos`)")
    parser.set_defaults(_input_kind=kind)
    if points:
        parser.add_argument("--points", metavar="CLOUD", help="extra free points (PLY or XYZ)")


def input_path(args: argparse.Namespace) -> Path:
    if args.demo and args.input:
        raise InputError("give either FILE or --demo NAME, not both")
    if args.demo:
        return demo(args.demo, args._input_kind).path
    if not args.input:
        raise InputError("no input: give FILE or --demo NAME")
    return Path(args.input)


def load_input_model(args: argparse.Namespace) -> Icadm:
    return load_model(input_path(args), points=getattr(args, "points", None))


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if np.isfinite(v) else None
    if isinstance(x, (np.bool_,)):
        return bool(x)
    if isinstance(x, Path):
        return str(x)
    return x


def write_json(path: str | Path, data: dict, *, force: bool = False) -> None:
    """Write a JSON report; never overwrite without --force."""
    path = Path(path)
    if path.exists() and not force:
        raise OutputExistsError(f"{path}: exists already (use --force to overwrite)")
    if not path.parent.exists():
        raise InputError(f"{path}: the folder {path.parent} does not exist")
    path.write_text(json.dumps(_jsonable(data), indent=1))


def dumps(data: dict) -> str:
    return json.dumps(_jsonable(data), indent=1)

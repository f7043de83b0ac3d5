"""The bundled demo assets.

Each kind of demo lives in its own folder of ``assets/`` with an ``index.json`` that lists its
demos (name, file, description, and for repair cases the ground truth). That index is the one
source of truth: ``bridgefield demos`` and every ``--demo NAME`` read it.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path


class UnknownDemoError(KeyError):
    def __str__(self) -> str:
        return str(self.args[0])


@dataclass(frozen=True)
class Demo:
    name: str
    kind: str  # "repair", "hybrid" or "frep"
    path: Path
    description: str
    truth: Path | None = None


def assets_dir() -> Path:
    env = os.environ.get("BRIDGEFIELD_ASSETS")
    return Path(env) if env else Path(__file__).resolve().parent.parent / "assets"


def all_demos() -> dict[str, Demo]:
    out: dict[str, Demo] = {}
    root = assets_dir()
    for index in sorted(root.glob("*/index.json")):
        data = json.loads(index.read_text())
        for d in data["demos"]:
            truth = index.parent / d["truth"] if d.get("truth") else None
            out[d["name"]] = Demo(d["name"], d["kind"], index.parent / d["file"], d["description"], truth)
    return out


def demo(name: str, kind: str | None = None) -> Demo:
    demos = all_demos()
    if name not in demos or (kind is not None and demos[name].kind != kind):
        names = ", ".join(n for n, d in demos.items() if kind is None or d.kind == kind)
        raise UnknownDemoError(f"unknown demo '{name}' (known: {names})")
    return demos[name]

"""Rebuild the repair demo assets: `python assets/repair/make_demos.py` (from the project root).

Each demo is an incomplete model (free points stored as unreferenced vertices) and the closed
mesh it was cut from (NAME.truth.ply). The cases themselves are defined in algorithms/cases.py.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent))

from algorithms.cases import demo_cases  # noqa: E402
from algorithms.io import save_mesh  # noqa: E402


def main() -> None:
    index = []
    for case in demo_cases():
        save_mesh(case.incomplete, HERE / f"{case.name}.ply", force=True, free_points=case.free_points)
        save_mesh(case.truth, HERE / f"{case.name}.truth.ply", force=True)
        index.append({"name": case.name, "kind": "repair", "file": f"{case.name}.ply",
                      "truth": f"{case.name}.truth.ply", "description": case.description,
                      "faces": int(case.incomplete.n_faces), "free_points": int(len(case.free_points))})
        print(f"{case.name}: {case.incomplete.n_faces} faces, {len(case.free_points)} free points")
    (HERE / "index.json").write_text(json.dumps({"demos": index}, indent=1) + "\n")
    _ = np


if __name__ == "__main__":
    main()

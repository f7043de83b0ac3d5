"""The repair's recorded stages as timeline frames (what the explorer shows at each step).

``algorithms.repair`` records five stages (input, bridges, holes, split, darned). The timeline
plays them in order and then fills the patches hole by hole: the darned stage's new faces are
cut into one frame per darned hole. Nothing is recomputed: the patch of a hole is recovered from
the recorded faces, which the repair appends hole after hole in the order of its hole records.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True, eq=False)
class StageFrame:
    name: str
    description: str
    holes: tuple[NDArray[np.float64], ...] = ()  # hole outlines (closed polylines)
    bridges: tuple[NDArray[np.float64], ...] = ()  # kept bridge chains so far
    vertices: NDArray[np.float64] | None = None  # the darned stage's vertices (patches index them)
    patches: NDArray[np.int64] | None = None  # (K, 3) patch faces shown at this frame


def patch_faces_by_hole(repair) -> list[NDArray[np.int64]]:
    """The darned stage's new faces, one array per darned hole (in the order they were darned,
    aligned with the hole records whose ``split_by`` is -1; a hole may get no face).

    A face belongs to the hole whose polygon holds all of its vertices that existed before
    darning (the others are the patch's own new vertices). Faces come hole after hole, so one
    pointer walks the holes; a face no hole claims stays with the current hole.
    """
    darned = next((s for s in repair.stages if s.name == "darned" and s.faces is not None), None)
    if darned is None:
        return []
    polys = [h.polygon for h in repair.holes if h.split_by < 0]
    faces = np.asarray(darned.faces, dtype=np.int64)
    new = faces[len(faces) - len(repair.new_faces):]
    if not polys:
        return [new] if len(new) else []
    n_old = max(max(p) for p in polys) + 1  # every vertex before darning lies on some hole (or below)
    sets = [set(map(int, p)) for p in polys]
    owner = np.zeros(len(new), dtype=np.int64)
    k = 0
    for i, f in enumerate(new):
        old = [int(v) for v in f if v < n_old]
        j = k
        while j < len(sets) and not all(v in sets[j] for v in old):
            j += 1
        if j < len(sets):
            k = j
        owner[i] = k
    return [new[owner == j] for j in range(len(polys))]


def stage_frames(repair) -> list[StageFrame]:
    """Timeline frames of a RepairResult: its recorded stages, then the patches filling."""
    out: list[StageFrame] = []
    darned = None
    for s in repair.stages:
        if s.name == "darned":
            darned = s
            continue
        out.append(StageFrame(s.name, s.description, tuple(s.holes), tuple(s.bridges)))
    if darned is None:
        return out
    per_hole = patch_faces_by_hole(repair)
    polys = [h.polygon for h in repair.holes if h.split_by < 0]
    V = darned.vertices
    bridges = tuple(darned.bridges)
    for k in range(1, len(per_hole) + 1):
        shown = np.vstack(per_hole[:k])
        last = k == len(per_hole)
        left = tuple(V[list(p)] for p in polys[k:]) if V is not None else ()
        out.append(StageFrame("darned" if last else "patches",
                              darned.description if last else f"patch {k} of {len(per_hole)} filled",
                              left, bridges, V, shown))
    if not per_hole:
        out.append(StageFrame("darned", darned.description, (), bridges, darned.vertices, np.zeros((0, 3), np.int64)))
    return out

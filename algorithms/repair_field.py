"""The force-line questions the repair pipeline asks the field (spec/repair.md §6 steps 1-3).

island_lines: candidate bridges between islands (step 1).
tunnel_lines: lines between the loops of one island and the tunnel rule (step 2).
split_line: a force line across one complex hole, from its point of maximal attraction (step 3).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from .boundary import LoopFrame
from .bridges import (
    FieldContext,
    _edges,
    attraction_index,
    field_context,
    find_candidate_bridges,
    local_maxima,
    loop_radius,
    trace_in_loop,
)
from .field.free_points import free_points
from .field.indicator import sources_from_frames
from .field.shielding import mesh_bvh
from .mesh import Icadm, Mesh
from .params import FieldParams
from .records import Cancelled, ForceLine


@dataclass(frozen=True, eq=False)
class LineSet:
    lc: float
    lines: tuple[ForceLine, ...]  # the lines that become bridge candidates
    all_lines: tuple[ForceLine, ...]  # every line traced (for the record)
    note: str = ""


def island_lines(model: Icadm, params: FieldParams, *, progress: Callable[[float, str], None] | None = None,
                 cancel: Callable[[], bool] | None = None) -> LineSet:
    """Step 1: for each island as base, lines from the local maxima of its attraction index."""
    bs = find_candidate_bridges(model, params, progress=progress, cancel=cancel)
    lines = tuple(c.line for c in bs.candidates)
    return LineSet(bs.lc, tuple(ln for ln in lines if ln.arrived), lines)


def _own_quality(ctx: FieldContext, frame: LoopFrame, starts: NDArray[np.int64], params: FieldParams,
                 cancel: Callable[[], bool] | None) -> tuple[float, list[ForceLine]]:
    """Best quality of the lines that cross the loop's own hole from the given start points."""
    best, out = 0.0, []
    for i in starts:
        if cancel is not None and cancel():
            raise Cancelled()
        ln = trace_in_loop(ctx, frame, int(i), replace(params, lc=None, step=None), lc=loop_radius(frame))
        out.append(ln)
        if ln.arrived:
            best = max(best, ln.quality)
    return best, out


def tunnel_lines(model: Icadm, frames: list[LoopFrame], loop_ids: list[int], params: FieldParams, *,
                 force: bool = False, cancel: Callable[[], bool] | None = None, starts_per_loop: int = 3) -> LineSet:
    """Step 2 (ICMT): lines between the loops of each island that has two or more loops.

    Two loops are joined by a tunnel when two or more force lines connect them and each of those
    lines has a quality above every other line of those two loops: the lines to other loops and
    the lines across each loop's own hole (which is what a loop that should simply be capped
    prefers). ``force`` (tunnels "on") joins the best connected pair without that comparison.
    """
    by_island: dict[int, list[int]] = {}
    for k in loop_ids:
        by_island.setdefault(frames[k].island, []).append(k)
    vert_loop = {int(v): k for k, f in enumerate(frames) for v in f.vertices}
    from .topology import islands

    _, lab = islands(model.mesh.faces)
    chosen: list[ForceLine] = []
    every: list[ForceLine] = []
    lc_seen = 0.0
    notes = []
    for isl, loops in by_island.items():
        if len(loops) < 2:
            continue
        sub = Icadm(Mesh(model.mesh.vertices, model.mesh.faces[lab == isl]), free_points=model.free_points)
        bs = find_candidate_bridges(sub, params, cancel=cancel)
        lc_seen = lc_seen or bs.lc
        lines = [c.line for c in bs.candidates]
        every += lines
        # lines between loops, by loop pair
        pair: dict[tuple[int, int], list[ForceLine]] = {}
        for ln in lines:
            if not ln.arrived:
                continue
            a, b = vert_loop.get(int(ln.start_vertex), -1), vert_loop.get(int(ln.end_vertex), -1)
            if a < 0 or b < 0 or a == b:
                continue
            pair.setdefault((min(a, b), max(a, b)), []).append(ln)
        if not pair:
            continue
        # lines across each loop's own hole, from its best start points
        ctx = field_context(sub, params)
        own: dict[int, float] = {}
        sub_loop = {int(f.vertices[0]): i for i, f in enumerate(ctx.frames)}
        for k in loops:
            fr = frames[k]
            si = sub_loop.get(int(fr.vertices[0]))
            w = bs.attraction[si] if si is not None and si < len(bs.attraction) else np.zeros(len(fr.vertices))
            mx = local_maxima(w)
            mx = mx[np.argsort(-w[mx])][:starts_per_loop] if len(mx) else np.array([int(np.argmax(w))])
            q, own_lines = _own_quality(ctx, fr, mx, params, cancel)
            every += own_lines
            own[k] = q
        for (a, b), lns in pair.items():
            others = [ln.quality for (p, q), l2 in pair.items() if (p, q) != (a, b) and ({p, q} & {a, b})
                      for ln in l2]
            rivals = max([own[a], own[b], *others], default=0.0)
            good = [ln for ln in lns if ln.quality > rivals]
            if len(good) >= 2 or (force and len(lns) >= 2):
                chosen += sorted(lns if force else good, key=lambda ln: -ln.quality)
                notes.append(f"loops {a} and {b}: {len(lns)} lines, best {max(ln.quality for ln in lns):.3g} "
                             f"vs rivals {rivals:.3g}: tunnel")
            else:
                notes.append(f"loops {a} and {b}: {len(good)} of {len(lns)} lines beat rivals {rivals:.3g}: "
                             "no tunnel")
    return LineSet(lc_seen, tuple(chosen), tuple(every), "; ".join(notes))


def split_line(model: Icadm, frame: LoopFrame, params: FieldParams, *, cancel: Callable[[], bool] | None = None,
               tries: int = 4, exclude_fraction: float = 0.2) -> tuple[ForceLine, int, int] | None:
    """Step 3: a force line across the hole ``frame`` from its point of maximal attraction.

    Sources: the hole's own points except a neighbourhood (exclude_fraction of the loop on each
    side) of the start; L_c = the hole's mean radius. Tries the local maxima of Omega in
    decreasing order; returns (line, start index, end index) for the first line that arrives at
    a point far enough from the start along the loop, or None.
    """
    n = len(frame.vertices)
    lc = float(params.lc) if params.lc is not None else loop_radius(frame)
    p = replace(params, lc=lc, step=params.step if params.step is not None else params.step_factor * lc)
    bvh = mesh_bvh(model.mesh) if p.shielding and model.mesh.n_faces else None
    fp = (free_points(model.free_points, kt=p.kt, rc=p.rc_factor * lc, kernel=p.g_kernel)
          if p.use_free_points and len(model.free_points) else None)
    ctx = FieldContext(model, p, (frame,), "single", np.zeros(1, dtype=np.int64),
                       sources_from_frames([frame], group="loop"), _edges((frame,)), lc, float(p.step), bvh, fp)
    omega, _ = attraction_index(ctx, exclude_fraction=exclude_fraction)
    w = omega[0]
    mx = local_maxima(w)
    order = mx[np.argsort(-w[mx])] if len(mx) else np.argsort(-w)
    pos = {int(v): i for i, v in enumerate(frame.vertices)}
    for i in order[:tries]:
        if cancel is not None and cancel():
            raise Cancelled()
        ln = trace_in_loop(ctx, frame, int(i), p, exclude_fraction=exclude_fraction, lc=lc)
        if not ln.arrived or int(ln.end_vertex) not in pos:
            continue
        j = pos[int(ln.end_vertex)]
        gap = min((j - i) % n, (i - j) % n)
        if gap >= 2:
            return ln, int(i), int(j)
    return None

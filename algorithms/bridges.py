"""Attraction index and candidate bridges between islands (spec/repair.md §4 end, §6 step 1).

For each base unit, sources = the boundary points of the other units; Omega (the attraction
index) at every base boundary point; force lines from the local maxima of Omega along each loop;
the lines that arrive are candidate bridges. Conflict resolution (crossing, too close, duplicate
bridges) is the repair pipeline's next step and is NOT done here.

Units (choice, documented): the islands when the model has two or more; with a single island
and several loops, the loops (the tunnel search of §6 step 2: e.g. a torus cut across its tube);
with a single loop, the hole-splitting rule of §6 step 3 (sources = the loop's own points except a
neighbourhood of a fifth of the loop on each side of the point) for Omega and `trace_from_vertex`.

L_c (choice for §6's "mean inter-island span near the island"): for every boundary point the
distance to the nearest boundary point of another unit; L_c = the mean of the smallest fifth of
these distances (the span where units face each other). For a single loop, its mean radius.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .boundary import LoopFrame, summarize
from .field.free_points import FreePoints, free_points
from .field.indicator import IndicatorField, Sources, sources_from_frames, top_normal
from .field.protocol import Biaf
from .field.quality import bridge_factors as _bridge_factors
from .field.shielding import Bvh, mesh_bvh
from .force_lines import make_targets, trace
from .mesh import Icadm
from .params import FieldParams
from .records import BridgeFactors, Cancelled, ForceLine

Arr = NDArray[np.float64]

__all__ = ["Candidate", "BridgeSet", "find_candidate_bridges", "trace_from_vertex", "trace_in_loop",
           "bridge_factors", "attraction_index", "local_maxima", "FieldContext", "field_context"]


def bridge_factors(a: Arr, tau_a: Arr, n_a: Arr, b: Arr, tau_b: Arr, n_b: Arr, params: FieldParams,
                   free_points: Arr | None = None, *, lc: float | None = None) -> BridgeFactors:
    """Quality of a straight bridge A -> B, eqs. 1-10 (see field.quality.bridge_factors)."""
    return _bridge_factors(a, tau_a, n_a, b, tau_b, n_b, params, free_points, lc=lc)


@dataclass(frozen=True, eq=False)
class Candidate:
    """One traced line from a base unit; factors of the straight segment start -> end if it arrived."""

    line: ForceLine
    factors: BridgeFactors | None
    start_loop: int
    start_index: int

    @property
    def quality(self) -> float:
        return self.line.quality


@dataclass(frozen=True, eq=False)
class BridgeSet:
    params: FieldParams
    lc: float
    attraction: tuple[NDArray[np.float64], ...]
    candidates: tuple[Candidate, ...]
    timings: dict[str, float]

    def arrived(self) -> list[Candidate]:
        return [c for c in self.candidates if c.line.arrived]


@dataclass(frozen=True, eq=False)
class FieldContext:
    """What every trace of one model needs: loop frames, units, L_c, step, BVH, free points."""

    model: Icadm
    params: FieldParams
    frames: tuple[LoopFrame, ...]
    unit_kind: str  # "island", "loop" or "single"
    unit: NDArray[np.int64]  # (n_loops,) unit of each loop
    sources: Sources  # every boundary point, group = unit
    edge: Arr  # (M,) longer boundary edge at each point
    lc: float
    step: float
    bvh: Bvh | None
    free: FreePoints | None


def _edges(frames: tuple[LoopFrame, ...]) -> Arr:
    out = []
    for f in frames:
        e = np.linalg.norm(np.roll(f.points, -1, axis=0) - f.points, axis=1)
        out.append(np.maximum(e, np.roll(e, 1)))
    return np.concatenate(out) if out else np.zeros(0)


def loop_radius(frame: LoopFrame) -> float:
    """Mean distance of the loop's points from their centroid (the hole's mean radius, §6 step 3)."""
    return float(np.linalg.norm(frame.points - frame.points.mean(axis=0), axis=1).mean())


def auto_lc(sources: Sources, *, positive: bool = False) -> float:
    """L_c: mean of the smallest fifth of the nearest distances to another unit's boundary.

    Where units touch at a vertex, normalisation split it into copies at one point: distances of
    zero. They count (tunnel_lines takes max(loop radius, this), and a smaller value there is what
    the sweep was measured with); ``positive``: they are left out. field_context needs that where
    they fill the smallest fifth: L_c = 0 stopped the field (random cuts of an icosphere, a torus
    and a subdivided box: an island touching another at a corner). (Leaving zeros out everywhere
    changed L_c of every cut with a pinched loop: on the sweep two featuretype handles were found,
    but the annulus gained one, and featuretype 8:1 full came back with a fill ballooning 48 % of
    the diagonal off.)"""
    groups = np.unique(sources.group)
    near = np.full(len(sources), np.inf)
    for g in groups:
        mine = sources.group == g
        if mine.all():
            continue
        d, _ = cKDTree(sources.points[~mine]).query(sources.points[mine])
        near[mine] = d
    near = near[np.isfinite(near)]
    if positive:
        near = near[near > 1e-12 * float(np.ptp(sources.points, axis=0).max(initial=0.0))]
    if not len(near):
        raise ValueError("L_c needs at least two units (islands or loops) apart")
    k = max(1, len(near) // 5)
    return float(np.mean(np.sort(near)[:k]))


def field_context(model: Icadm, params: FieldParams) -> FieldContext:
    """Loop frames, units, L_c and step (automatic unless given), BVH (full mode), free points (full mode)."""
    frames = tuple(summarize(model, charge=params.charge).loops)
    isl = np.array([f.island for f in frames], dtype=np.int64)
    if len(np.unique(isl)) >= 2:
        kind, unit = "island", isl
    elif len(frames) >= 2:
        kind, unit = "loop", np.arange(len(frames), dtype=np.int64)
    else:
        kind, unit = "single", np.zeros(len(frames), dtype=np.int64)
    src = sources_from_frames(frames, group="island" if kind == "island" else "loop")
    if params.lc is not None:
        lc = float(params.lc)
    elif kind == "single":
        lc = loop_radius(frames[0]) if frames else 1.0
    else:
        lc = auto_lc(src) or auto_lc(src, positive=True)  # (only copies of touching vertices nearest: 0)
    step = float(params.step) if params.step is not None else params.step_factor * lc
    bvh = mesh_bvh(model.mesh) if params.shielding and model.mesh.n_faces else None
    fp = None
    if params.use_free_points and len(model.free_points):
        fp = free_points(model.free_points, kt=params.kt, rc=params.rc_factor * lc, kernel=params.g_kernel)
    return FieldContext(model, params, frames, kind, unit, src, _edges(frames), lc, step, bvh, fp)


def _window(n: int, fraction: float) -> int:
    return int(round(fraction * n))


def attraction_index(ctx: FieldContext, *, exclude_fraction: float = 0.2) -> tuple[tuple[Arr, ...], Arr]:
    """Omega at every boundary point (spec §4): n from (16a) with n . n_O > 0, Omega = |H n| when
    (H n) . b_O > 0 else 0. Sources: the other units (in "single" mode, the own loop minus the
    neighbourhood). Returns Omega per loop and the normals (M, 3) of all points."""
    S = ctx.sources
    field = IndicatorField(S, ctx.params, ctx.lc, bvh=ctx.bvh, free=ctx.free)
    if ctx.unit_kind == "single":
        win = np.array([_window(int(n), exclude_fraction) for n in S.loop_len])
        ev = field.evaluate(S.points, x_vertex=S.vertex, x_loop=S.loop, x_pos=S.pos, x_window=win)
    else:
        # x_loop / x_pos without a window exclude nothing: they mark consecutive points (full mode's
        # coherence across points, FieldParams.point_stride)
        ev = field.evaluate(S.points, x_vertex=S.vertex, x_group=S.group, x_loop=S.loop, x_pos=S.pos)
    n, ten = top_normal(ev.H, S.tangent, S.normal)  # (16a)
    f = np.einsum("nij,nj->ni", ev.H, n)
    omega = np.where((f * S.outward).sum(axis=1) > 0, ten, 0.0)
    out, a = [], 0
    for fr in ctx.frames:
        out.append(omega[a:a + len(fr.vertices)])
        a += len(fr.vertices)
    return tuple(out), n


def local_maxima(omega: Arr, *, floor: float = 0.0) -> NDArray[np.int64]:
    """Indices of the local maxima of Omega along a closed loop (Omega > floor, >= both
    neighbours, > the previous one so a plateau counts once)."""
    w = np.asarray(omega, dtype=np.float64)
    if not len(w):
        return np.zeros(0, dtype=np.int64)
    prev, nxt = np.roll(w, 1), np.roll(w, -1)
    return np.flatnonzero((w > floor) & (w > prev) & (w >= nxt))


def _unit_tools(ctx: FieldContext, unit: int, params: FieldParams) -> tuple:
    """What every line from one base unit shares: its field, targets and avoid tree (built once)."""
    S = ctx.sources
    other = S.group != unit
    sub = S.subset(other)
    field = Biaf(IndicatorField(sub, params, ctx.lc, bvh=ctx.bvh, free=ctx.free))
    tg = make_targets(sub.points, ctx.edge[other], ctx.step, vertex=sub.vertex, island=sub.island)
    mine = S.points[~other]
    return field, tg, cKDTree(mine) if len(mine) else None


def _trace_unit(ctx: FieldContext, loop: int, index: int, params: FieldParams, tools: tuple | None = None) -> ForceLine:
    """A line from point `index` of loop `loop` with sources = the other units' boundary points."""
    fr = ctx.frames[loop]
    field, tg, avoid = tools if tools is not None else _unit_tools(ctx, int(ctx.unit[loop]), params)
    return trace(field, fr.points[index], fr.tangent[index], fr.normal[index], params, tg, step=ctx.step,
                 avoid=avoid, start_vertex=int(fr.vertices[index]), start_island=fr.island)


def trace_in_loop(model_or_ctx: Icadm | FieldContext | LoopFrame | None, frame: LoopFrame, start_index: int,
                  params: FieldParams, *,
                  exclude_fraction: float = 0.2, lc: float | None = None, bvh: Bvh | None = None,
                  free: FreePoints | None = None) -> ForceLine:
    """Trace inside ONE hole (hole splitting, §6 step 3).

    Sources and targets: the loop's own points except the neighbourhood of `start_index`
    (exclude_fraction of the loop on each side); a line ending inside that neighbourhood is
    TURNED_BACK. L_c = params.lc if given, else the hole's mean radius (or ``lc``); the step is
    params.step or step_factor * L_c. Full mode uses the model's triangles (BVH) and free points
    when a model or context is given (or ``bvh`` / ``free``).
    """
    if isinstance(model_or_ctx, FieldContext):
        model, bvh, free = model_or_ctx.model, bvh or model_or_ctx.bvh, free or model_or_ctx.free
    elif isinstance(model_or_ctx, Icadm):
        model = model_or_ctx
    else:  # None or a LoopFrame: no triangles, no free points (light-mode behaviour)
        model = None
    lc_ = float(params.lc) if params.lc is not None else (lc if lc is not None else loop_radius(frame))
    step = float(params.step) if params.step is not None else params.step_factor * lc_
    if params.shielding and bvh is None and model is not None and model.mesh.n_faces:
        bvh = mesh_bvh(model.mesh)
    if params.use_free_points and free is None and model is not None and len(model.free_points):
        free = free_points(model.free_points, kt=params.kt, rc=params.rc_factor * lc_, kernel=params.g_kernel)
    n = len(frame.vertices)
    src = sources_from_frames([frame], group="loop")
    k = np.arange(n)
    dp = np.abs(k - start_index)
    dp = np.minimum(dp, n - dp)
    win = _window(n, exclude_fraction)
    inside = dp <= win
    sub = src.subset(~inside)
    edge = _edges((frame,))
    field = Biaf(IndicatorField(sub, params, lc_, bvh=bvh, free=free))
    tg = make_targets(sub.points, edge[~inside], step, vertex=sub.vertex, island=sub.island)
    line = trace(field, frame.points[start_index], frame.tangent[start_index], frame.normal[start_index], params, tg,
                 step=step, avoid=frame.points[inside & (k != start_index)],
                 start_vertex=int(frame.vertices[start_index]), start_island=frame.island)
    return line


_LAST_CONTEXT: list = []  # (model, params, context) of the last inspector click


def _cached_context(model: Icadm, params: FieldParams) -> FieldContext:
    """field_context, reused while the model object and the parameters stay the same (the
    inspector clicks one vertex after another on one model)."""
    if _LAST_CONTEXT and _LAST_CONTEXT[0][0] is model and _LAST_CONTEXT[0][1] == params:
        return _LAST_CONTEXT[0][2]
    ctx = field_context(model, params)
    _LAST_CONTEXT[:] = [(model, params, ctx)]
    return ctx


def _locate(frames: tuple[LoopFrame, ...], vertex: int) -> tuple[int, int]:
    for li, fr in enumerate(frames):
        hit = np.flatnonzero(fr.vertices == vertex)
        if len(hit):
            return li, int(hit[0])
    raise ValueError(f"vertex {vertex} is not a boundary vertex")


def trace_from_vertex(model: Icadm, params: FieldParams, vertex: int, *, ctx: FieldContext | None = None) -> ForceLine:
    """The inspector's click: trace from one boundary vertex. Sources = the other units' boundaries
    (islands, or loops of a single island); with a single loop, the rest of its own loop minus
    the excluded neighbourhood (trace_in_loop)."""
    ctx = ctx or _cached_context(model, params)
    loop, idx = _locate(ctx.frames, int(vertex))
    if ctx.unit_kind == "single":
        return trace_in_loop(ctx, ctx.frames[loop], idx, ctx.params, lc=ctx.lc)
    return _trace_unit(ctx, loop, idx, ctx.params)


def find_candidate_bridges(model: Icadm, params: FieldParams, *, progress: Callable[[float, str], None] | None = None,
                           cancel: Callable[[], bool] | None = None, attraction_floor: float = 0.05) -> BridgeSet:
    """§6 step 1 up to conflict resolution: Omega at every boundary point, force lines from the
    local maxima of Omega (those above attraction_floor x the loop's maximum), every line kept
    (arrived or not) with the factors of the straight segment start -> end when it arrived.

    Raises records.Cancelled when cancel() returns True. With a single loop nothing is traced
    (hole splitting belongs to the repair pipeline) but Omega is reported.
    """
    t_all = time.perf_counter()
    timings: dict[str, float] = {}

    def check() -> None:
        if cancel is not None and cancel():
            raise Cancelled()

    def report(frac: float, what: str) -> None:
        if progress is not None:
            progress(frac, what)

    t = time.perf_counter()
    report(0.0, "boundary frames")
    ctx = field_context(model, params)
    if not ctx.frames:
        return BridgeSet(params, float(params.lc or 0.0), (), (), {"total": time.perf_counter() - t_all})
    params_used = replace(params, lc=ctx.lc, step=ctx.step)
    ctx = replace(ctx, params=params_used)
    timings["setup"] = time.perf_counter() - t
    check()
    t = time.perf_counter()
    report(0.05, "attraction index")
    omega, _ = attraction_index(ctx)
    timings["attraction"] = time.perf_counter() - t
    check()
    starts = []
    if ctx.unit_kind != "single":
        for li, w in enumerate(omega):
            mx = float(w.max()) if len(w) else 0.0
            starts += [(li, int(i)) for i in local_maxima(w, floor=attraction_floor * mx)]
    t = time.perf_counter()
    cands = []
    fp = ctx.model.free_points if params.use_free_points else None
    tools: dict[int, tuple] = {}
    for k, (li, i) in enumerate(starts):  # lines are independent; traced one after the other
        check()
        report(0.1 + 0.9 * k / max(len(starts), 1), f"tracing line {k + 1} of {len(starts)}")
        u = int(ctx.unit[li])
        if u not in tools:
            tools[u] = _unit_tools(ctx, u, params_used)
        line = _trace_unit(ctx, li, i, params_used, tools[u])
        fac = None
        if line.arrived:
            fa, ia = li, i
            fb, ib = _locate(ctx.frames, line.end_vertex)
            A, B = ctx.frames[fa], ctx.frames[fb]
            fac = bridge_factors(A.points[ia], A.tangent[ia], A.normal[ia], B.points[ib], B.tangent[ib], B.normal[ib],
                                 params_used, fp, lc=ctx.lc)
        cands.append(Candidate(line, fac, li, i))
    timings["tracing"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t_all
    report(1.0, "done")
    return BridgeSet(params_used, ctx.lc, omega, tuple(cands), timings)


"""Force lines (spec/repair.md §5): the simple tracer (2004) and the predictor-corrector (2010, F4.1).

A line starts at a boundary point and follows the force F = H n of a missing-surface field (any
object of field/protocol.py). Every step is recorded (point, normal, force, tension) in a
records.ForceLine, which is what the explorer animates. The steps of one line are sequential,
hence the Python loop; lines are independent of each other.

How a line ends (records.STATUSES), checked in this order after each step:
- ARRIVED: the point came within reach of a target boundary point (reach = max(step, 0.55 x the
  longer boundary edge at the target), so a line cannot slip between two sparse targets); the
  line then ends on that point, the second supporting point of the bridge;
- TURNED_BACK: once farther than 2 steps from its start, it came within one step of an "avoid"
  point (the base island's boundary, or the excluded neighbourhood of the start in a hole);
- TOO_WEAK: |H n| < threshold x |H n| at the start;
- STALLED: the force reversed against the last direction (F_k . p_{k-1} < 0): an equilibrium
  between attraction and repulsion (what light mode does with a heavy-tailed q1, spec §5);
- STEP_LIMIT: params.max_steps points recorded.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .field import light_tracer as lt
from .field.protocol import Biaf, MissingSurfaceField
from .params import FieldParams
from .records import ARRIVED, STALLED, STEP_LIMIT, TOO_WEAK, TURNED_BACK, Cancelled, ForceLine

Arr = NDArray[np.float64]
PC_SAMPLES = 5  # predictor-corrector: points tried on [P1' - d N1', P1' + d N1'] (the centre included)
FUSED_CHUNK = 256  # steps per call of the fused light-mode tracer (cancel is checked between calls)
_STATUS = {lt.ARRIVED_C: ARRIVED, lt.TURNED_BACK_C: TURNED_BACK, lt.TOO_WEAK_C: TOO_WEAK, lt.STALLED_C: STALLED,
           lt.STEP_LIMIT_C: STEP_LIMIT}


@dataclass(frozen=True, eq=False)
class Targets:
    """T boundary points a line may arrive at: points (T, 3), reach (T,), vertex and island (T,)."""

    points: Arr
    reach: Arr
    vertex: NDArray[np.int64]
    island: NDArray[np.int64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "_rmax", float(self.reach.max()) if len(self.reach) else 0.0)

    @cached_property
    def _tree(self) -> cKDTree | None:
        """Built on the first hit() (the Python tracer's); the fused tracer tests the points itself."""
        return cKDTree(self.points) if len(self.points) else None

    def hit(self, x: Arr) -> int:
        """Index of the nearest target within its reach of x, or -1."""
        tree = self._tree
        if tree is None:
            return -1
        dist, idx = tree.query(x, k=min(4, len(self.points)), distance_upper_bound=self._rmax)  # type: ignore
        dist, idx = np.atleast_1d(dist), np.atleast_1d(idx)
        ok = np.isfinite(dist)
        if not ok.any():
            return -1
        ok[ok] = dist[ok] < self.reach[idx[ok]]
        return int(idx[np.argmax(ok)]) if ok.any() else -1


def make_targets(points: Arr, edge: Arr, step: float, *, vertex: NDArray[np.int64] | None = None,
                 island: NDArray[np.int64] | None = None) -> Targets:
    """Targets with reach max(step, 0.55 * edge) (edge: the longer boundary edge at each point)."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    n = len(points)
    return Targets(points, np.maximum(step, 0.55 * np.asarray(edge, dtype=np.float64)),
                   np.full(n, -1, dtype=np.int64) if vertex is None else np.asarray(vertex, dtype=np.int64),
                   np.full(n, -1, dtype=np.int64) if island is None else np.asarray(island, dtype=np.int64))


def trace(field: MissingSurfaceField, start_point: Arr, start_tangent: Arr, start_normal: Arr,
          params: FieldParams, targets: Targets, *, step: float, avoid: Arr | cKDTree | None = None,
          start_vertex: int = -1, start_island: int = -1,
          cancel: Callable[[], bool] | None = None) -> ForceLine:
    """Trace one force line from a boundary point (spec §5), recording every step.

    start_tangent: tau at the origin (the normal there comes from (16a) with n . start_normal > 0);
    step: the step s; targets: where the line may arrive; avoid (K, 3): points whose one-step
    neighbourhood means "turned back" (or a prebuilt cKDTree of them). params.tracer picks the
    simple or the predictor-corrector tracer; params.deviation is d in steps; params.threshold
    and max_steps as in the module doc.
    """
    x = np.asarray(start_point, dtype=np.float64).copy()
    if isinstance(avoid, cKDTree):
        avoid_pts: Arr = np.asarray(avoid.data)
    else:
        avoid_pts = np.asarray(avoid, dtype=np.float64).reshape(-1, 3) if avoid is not None else np.zeros((0, 3))
    tau0 = np.asarray(start_tangent, dtype=np.float64)
    s0 = field.sample(x, tau0, np.asarray(start_normal, dtype=np.float64))  # (16a)
    pts, nrm, frc, ten = [x.copy()], [s0.normal if s0.normal is not None else np.zeros(3)], [
        s0.force if s0.force is not None else np.zeros(3)], [s0.tension]
    t0 = s0.tension
    floor = params.threshold * t0

    def done(status: str, end: int = -1) -> ForceLine:
        return ForceLine(np.array(pts), np.array(nrm), np.array(frc), np.array(ten), status, int(start_vertex),
                         int(start_island), int(targets.vertex[end]) if end >= 0 else -1,
                         int(targets.island[end]) if end >= 0 else -1)

    if s0.force is None or t0 <= 0 or s0.normal is None:
        return done(TOO_WEAK)
    f, n = s0.force, s0.normal
    if isinstance(field, Biaf) and len(field.field.sources):
        rec = (pts, nrm, frc, ten)
        return _trace_fused(field, x, f, n, params, targets, step, avoid_pts, floor, cancel, rec, done)
    # the Python loop (other fields): a k-d tree of the points to avoid
    avoid_tree = avoid if isinstance(avoid, cKDTree) else (cKDTree(avoid_pts) if len(avoid_pts) else None)
    dev = params.deviation * step
    offs = np.linspace(-1.0, 1.0, PC_SAMPLES)
    simple = params.tracer == "simple"
    start = pts[0]
    while True:  # sequential: each step starts where the previous one ended
        if cancel is not None and cancel():
            raise Cancelled()
        if len(pts) >= params.max_steps:
            return done(STEP_LIMIT)
        p = f / math.sqrt(float(f @ f))
        if simple:  # 2004: X_{k+1} = X_k + s F_k / |F_k|
            x_new = x + step * p
        else:  # 2010 F4.1: predictor, then the point of maximum potential across the predicted normal
            pred = x + step * p
            s1 = field.sample(pred, p, n)
            n1 = s1.normal if s1.normal is not None else n
            cand = pred[None] + (dev * offs)[:, None] * n1[None]
            psi = [s1.potential if abs(o) < 1e-12 and s1.potential is not None else field.potential(c, p)
                   for c, o in zip(cand, offs)]
            x_new = cand[int(np.argmax(psi))]
        tang = x_new - x
        tang /= max(math.sqrt(float(tang @ tang)), 1e-300)
        s = field.sample(x_new, tang, n)  # (16b): n . p = 0, sign n . n_prev > 0
        x = x_new
        hit = targets.hit(x)
        if hit >= 0:
            end = targets.points[hit]
            pts.append(end.copy())
            se = field.sample(end, end - pts[-2], n)
            nrm.append(se.normal if se.normal is not None else n)
            frc.append(se.force if se.force is not None else np.zeros(3))
            ten.append(se.tension)
            return done(ARRIVED, hit)
        sf = s.force
        tension = math.sqrt(float(sf @ sf)) if sf is not None else 0.0
        pts.append(x)
        nrm.append(s.normal if s.normal is not None else n)
        frc.append(sf if sf is not None else np.zeros(3))
        ten.append(tension)
        if avoid_tree is not None:
            dx = x - start
            if float(dx @ dx) > 4 * step * step and avoid_tree.query(x)[0] < step:
                return done(TURNED_BACK)
        if sf is None or s.normal is None or tension < floor or tension <= 0:
            return done(TOO_WEAK)
        if float(sf @ tang) < 0:
            return done(STALLED)
        f, n = sf, s.normal


def _trace_fused(field: Biaf, x: Arr, f: Arr, n: Arr, params: FieldParams, targets: Targets, step: float,
                 avoid_pts: Arr, floor: float, cancel: Callable[[], bool] | None, rec: tuple,
                 done: Callable[[str, int], ForceLine]) -> ForceLine:
    """The tracer's loop (simple or predictor-corrector) in numba (field/light_tracer.py) for the
    BIAF (light or full mode): the same steps as trace's Python loop, FUSED_CHUNK steps per call."""
    F = field.field
    S = F.sources
    pts, nrm, frc, ten = rec
    state = np.array([x, f, n], dtype=np.float64)
    start = np.array(pts[0], dtype=np.float64)
    avoid = np.ascontiguousarray(avoid_pts, dtype=np.float64)
    tg = np.ascontiguousarray(targets.points, dtype=np.float64)
    reach = np.ascontiguousarray(targets.reach, dtype=np.float64)
    chunk = min(FUSED_CHUNK, params.max_steps)
    offs = np.linspace(-1.0, 1.0, PC_SAMPLES)
    la = (S.points, S.tangent, S.outward, S.charge, F.lc * F.lc, float(F.params.ki), F.kernel, F._prune2)
    fa = F.one_point_args()
    ox, on, of = np.empty((chunk, 3)), np.empty((chunk, 3)), np.empty((chunk, 3))
    ot = np.empty(chunk)
    while True:  # sequential: each chunk continues the line where the last one stopped
        if cancel is not None and cancel():
            raise Cancelled()
        k, code, hit = lt.tracer_chunk(state, start, len(pts), params.max_steps, chunk, float(step), float(floor),
                                       F.full, la, fa, tg, reach, avoid, ox, on, of, ot,
                                       params.tracer != "simple", float(params.deviation * step), offs)
        pts.extend(ox[:k].copy())
        nrm.extend(on[:k].copy())
        frc.extend(of[:k].copy())
        ten.extend(ot[:k].tolist())
        if code != lt.CONTINUE:
            return done(_STATUS[code], int(hit))

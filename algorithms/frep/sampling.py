"""Points on the surface (spec/frep.md §2, the paper's §3, §3.1).

1. Quadtree over the camera plane (xy): the square is split into 4 recursively, and every block
   whose interval extension of F over block × [z0, z1] is surely negative (surely outside) is
   dropped, down to level QLEV (cell size S_xy = 1/2^QLEV of the domain).
2. At every remaining cell a ray (a column, along z) is cast through the cell centre and halved
   recursively down to S_z = 1/2^BLEV; halves whose interval of F is surely negative or surely
   positive hold no crossing and are dropped, and **all** crossings are kept.
3. At level BLEV each remaining segment is tested by the sign of F at its two nodes; a sign change
   is a surface point, placed by linear interpolation inside the segment (precision S_z).

All columns of one level are processed together (vectorised across columns and segments). The
voxels so formed are empty, surface or inside: each column's inside nodes form runs [b, t]
(node indices on the BLEV grid), one run between an entry (bottom point) and an exit (top point).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .interval import Interval
from .objects import FRepObject

BOTTOM, TOP = 0, 1


@dataclass(frozen=True)
class SamplingParams:
    qlev: int = 6  # quadtree depth: S_xy = size / 2^qlev
    blev: int = 12  # ray subdivision depth: S_z = size / 2^blev

    def __post_init__(self) -> None:
        if not (isinstance(self.qlev, (int, np.integer)) and 1 <= self.qlev <= 11):
            raise ValueError(f"qlev must be an integer in 1..11, got {self.qlev!r}")
        if not (isinstance(self.blev, (int, np.integer)) and 1 <= self.blev <= 30):
            raise ValueError(f"blev must be an integer in 1..30, got {self.blev!r}")


@dataclass(frozen=True, eq=False)
class Samples:
    """Surface points and the runs of inside nodes of every column.

    points: (P, 3) positions; point_col: (P, 2) column (i, j); point_kind: (P,) BOTTOM (entry,
    outside below) or TOP (exit); point_run: (P,) run index.
    runs: (R,) per run column i, j, first and last inside node b <= t, bottom and top point ids.
    quadtree: the kept blocks per level, (n_l, 2) integer block coordinates (for replay).
    """

    params: SamplingParams
    points: NDArray[np.float64]
    point_col: NDArray[np.int64]
    point_kind: NDArray[np.int8]
    point_run: NDArray[np.int64]
    run_i: NDArray[np.int64]
    run_j: NDArray[np.int64]
    run_b: NDArray[np.int64]
    run_t: NDArray[np.int64]
    run_bottom: NDArray[np.int64]
    run_top: NDArray[np.int64]
    columns: NDArray[np.int64]  # (C, 2) the columns (cells at QLEV) that were not culled
    quadtree: list[NDArray[np.int64]] = field(repr=False)
    interval_evaluations: int = 0
    point_evaluations: int = 0

    @property
    def cell(self) -> float:
        return 1.0 / 2**self.params.qlev


def quadtree_columns(obj: FRepObject, qlev: int) -> tuple[NDArray[np.int64], list[NDArray[np.int64]], int]:
    """Cells of level qlev not proven outside, with the kept blocks of every level."""
    lo, size = obj.lo, obj.size
    zi = Interval(lo[2], lo[2] + size[2])
    blocks = np.zeros((1, 2), dtype=np.int64)
    levels = []
    evals = 0
    for level in range(qlev + 1):  # one pass per level; each pass is vectorised over the blocks
        s = 1.0 / 2**level
        x0 = lo[0] + blocks[:, 0] * s * size[0]
        y0 = lo[1] + blocks[:, 1] * s * size[1]
        f = obj.interval(Interval(x0, x0 + s * size[0]), Interval(y0, y0 + s * size[1]), zi)
        evals += len(blocks)
        blocks = blocks[f.hi >= 0]  # drop blocks surely outside
        levels.append(blocks)
        if level < qlev:
            blocks = (2 * blocks[:, None, :] + np.array([[0, 0], [1, 0], [0, 1], [1, 1]])[None]).reshape(-1, 2)
    return blocks, levels, evals


def sample(obj: FRepObject, params: SamplingParams | None = None, **kw: int) -> Samples:
    params = params or SamplingParams(**kw)
    qlev, blev = params.qlev, params.blev
    lo, size = obj.lo, obj.size
    cols, levels, ievals = quadtree_columns(obj, qlev)
    n = 2**qlev
    cx = lo[0] + (cols[:, 0] + 0.5) / n * size[0]
    cy = lo[1] + (cols[:, 1] + 0.5) / n * size[1]
    # binary subdivision of every column: segments (column, k) at level l cover [k, k+1] / 2^l
    seg_c = np.arange(len(cols))
    seg_k = np.zeros(len(cols), dtype=np.int64)
    for level in range(blev + 1):  # sequential over levels, vectorised over all segments of a level
        if not len(seg_c):
            break
        s = size[2] / 2**level
        z0 = lo[2] + seg_k * s
        f = obj.interval(Interval(cx[seg_c]), Interval(cy[seg_c]), Interval(z0, z0 + s))
        ievals += len(seg_c)
        keep = (f.lo <= 0) & (f.hi >= 0)  # surely outside or surely inside: no crossing
        seg_c, seg_k = seg_c[keep], seg_k[keep]
        if level < blev:
            seg_c = np.repeat(seg_c, 2)
            seg_k = (2 * seg_k[:, None] + np.array([0, 1])).ravel()
    nz = 2**blev
    sz = size[2] / nz
    # leaves: sign of F at the two nodes
    z0 = lo[2] + seg_k * sz
    p0 = np.stack([cx[seg_c], cy[seg_c], z0], axis=1)
    p1 = p0 + np.array([0.0, 0.0, sz])
    f0, f1 = obj.value(p0), obj.value(p1)
    pevals = 2 * len(seg_c)
    cross = (f0 >= 0) != (f1 >= 0)
    c_col, c_k, f0, f1 = seg_c[cross], seg_k[cross], f0[cross], f1[cross]
    t = np.clip(f0 / (f0 - f1), 0.0, 1.0)  # linear interpolation inside the segment
    c_z = lo[2] + (c_k + t) * sz
    c_kind = np.where(f1 >= 0, BOTTOM, TOP).astype(np.int8)
    c_node = np.where(c_kind == BOTTOM, c_k + 1, c_k)  # first / last inside node
    # the domain's floor and ceiling close columns that are inside there
    pe = np.stack([np.r_[cx, cx], np.r_[cy, cy], np.r_[np.full(len(cols), lo[2]), np.full(len(cols), lo[2] + size[2])]],
                  axis=1)
    fe = obj.value(pe)
    pevals += len(pe)
    floor_in = np.flatnonzero(fe[: len(cols)] >= 0)
    ceil_in = np.flatnonzero(fe[len(cols):] >= 0)
    c_col = np.r_[c_col, floor_in, ceil_in]
    c_z = np.r_[c_z, np.full(len(floor_in), lo[2]), np.full(len(ceil_in), lo[2] + size[2])]
    c_kind = np.r_[c_kind, np.full(len(floor_in), BOTTOM, np.int8), np.full(len(ceil_in), TOP, np.int8)]
    c_node = np.r_[c_node, np.zeros(len(floor_in), np.int64), np.full(len(ceil_in), nz, np.int64)]
    # order by column then height; entries and exits alternate along a column
    order = np.lexsort((c_kind, c_node, c_col))
    c_col, c_z, c_kind, c_node = c_col[order], c_z[order], c_kind[order], c_node[order]
    ok = _alternating(c_col, c_kind)
    c_col, c_z, c_kind, c_node = c_col[ok], c_z[ok], c_kind[ok], c_node[ok]
    points = np.stack([cx[c_col], cy[c_col], c_z], axis=1)
    npts = len(points)
    bottoms = np.arange(0, npts, 2)
    tops = bottoms + 1
    run_of = np.repeat(np.arange(npts // 2), 2)
    return Samples(params, points, cols[c_col], c_kind, run_of,
                   cols[c_col[bottoms], 0], cols[c_col[bottoms], 1], c_node[bottoms], c_node[tops],
                   bottoms, tops, cols, levels, ievals, pevals)


def _alternating(col: NDArray[np.int64], kind: NDArray[np.int8]) -> NDArray[np.bool_]:
    """Keep whole columns whose crossings go BOTTOM, TOP, BOTTOM, TOP ... (always, for a
    consistent sign test; a column that fails is dropped rather than linked wrongly)."""
    if not len(col):
        return np.zeros(0, dtype=bool)
    start = np.r_[True, col[1:] != col[:-1]]
    idx = np.arange(len(col))
    first = np.maximum.accumulate(np.where(start, idx, 0))
    pos = idx - first
    good = kind == (pos % 2)
    counts = np.bincount(col, minlength=col.max() + 1)
    bad_cols = np.unique(col[~good])
    bad = np.isin(col, bad_cols) | (counts[col] % 2 == 1)
    return ~bad

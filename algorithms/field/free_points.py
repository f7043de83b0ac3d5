"""Free points: the effective length q2 (eq. 4) and the point-cloud field PRAF (spec §8).

Each free point P_i is the source of G(R) = k_t/(1-k_t) * kernel(R / R_c) (quality.free_point_g).
Two lookups of the free points near a place:
- a scipy cKDTree (``FreePoints.tree``) for the reference q2 of one bridge (quality.q2_segment)
  and for PRAF's normals;
- a uniform grid (cell = the G cutoff) read by the numba field kernel, which needs q2 for
  millions of point x source segments: the grid's cell lists are flat arrays (sorted by cell).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .quality import free_point_g, g0, g_cutoff

MAX_CELLS = 2_000_000
Q2_SAMPLES = 8  # midpoint-rule samples along a segment in the field kernel


@dataclass(frozen=True, eq=False)
class FreePoints:
    """P free points with the field G; grid arrays for the numba kernel.

    origin (3,), cell (float), dims (3,) int, cell_start (C + 1,), cell_points (P, 3) sorted by cell.
    """

    points: NDArray[np.float64]
    kt: float
    rc: float
    kernel: str
    cutoff: float
    origin: NDArray[np.float64]
    cell: float
    dims: NDArray[np.int64]
    cell_start: NDArray[np.int64]
    cell_points: NDArray[np.float64]
    g_max: float  # an estimate of the largest sum_i G anywhere (for pruning far pairs)
    tree: cKDTree = field(repr=False)

    @property
    def kernel_code(self) -> int:
        return 0 if self.kernel == "gauss" else 1


def free_points(points: NDArray[np.float64], *, kt: float, rc: float, kernel: str = "gauss") -> FreePoints:
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    cut = g_cutoff(rc, kernel)
    tree = cKDTree(p) if len(p) else cKDTree(np.zeros((1, 3)))
    if len(p) == 0:
        z = np.zeros(3)
        return FreePoints(p, kt, rc, kernel, cut, z, 1.0, np.ones(3, dtype=np.int64), np.zeros(2, dtype=np.int64),
                          p, 0.0, tree)
    lo = p.min(axis=0) - cut
    hi = p.max(axis=0) + cut
    cell = cut
    while True:
        dims = np.maximum(np.ceil((hi - lo) / cell).astype(np.int64), 1)
        if int(np.prod(dims)) <= MAX_CELLS:
            break
        cell *= 1.5
    ijk = np.minimum(((p - lo) / cell).astype(np.int64), dims - 1)
    lin = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
    order = np.argsort(lin, kind="stable")
    counts = np.bincount(lin, minlength=int(np.prod(dims)))
    start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    # an estimate of max sum G over space, for pruning: sum G is largest at the free points
    # themselves (G decreases with distance); 1.25 x the largest sum at a free point + G's tail
    k = min(len(p), 32)
    dist, _ = tree.query(p, k=k, distance_upper_bound=cut)
    dist = np.where(np.isfinite(dist), dist, np.inf)
    gs = free_point_g(dist, kt, rc, kernel).sum(axis=1)
    gmax = 1.25 * float(gs.max()) + g0(kt) * 1e-4 * len(p)
    return FreePoints(p, kt, rc, kernel, cut, lo, float(cell), dims, start, np.ascontiguousarray(p[order]), gmax, tree)


@numba.njit(cache=True, fastmath=True)
def g_sum(y, origin, cell, dims, cell_start, cell_points, g0v, rc2, cut2, kernel):
    """sum_i G(|P_i - y|) over the free points within the cutoff (grid lookup)."""
    total = 0.0
    ci = np.empty(3, dtype=np.int64)
    for k in range(3):
        ci[k] = int(np.floor((y[k] - origin[k]) / cell))
        if ci[k] < -1 or ci[k] > dims[k]:
            return 0.0
    for a in range(max(ci[0] - 1, 0), min(ci[0] + 2, dims[0])):
        for b in range(max(ci[1] - 1, 0), min(ci[1] + 2, dims[1])):
            for c in range(max(ci[2] - 1, 0), min(ci[2] + 2, dims[2])):
                lin = (a * dims[1] + b) * dims[2] + c
                for m in range(cell_start[lin], cell_start[lin + 1]):
                    dx = cell_points[m, 0] - y[0]
                    dy = cell_points[m, 1] - y[1]
                    dz = cell_points[m, 2] - y[2]
                    r2 = dx * dx + dy * dy + dz * dz
                    if r2 < cut2:
                        if kernel == 0:
                            total += g0v * np.exp(-r2 / rc2)
                        else:
                            total += g0v / (1.0 + r2 / rc2)
    return total


@numba.njit(cache=True, fastmath=True)
def q2_kernel(x, o, length, origin, cell, dims, cell_start, cell_points, g0v, rc2, cut2, kernel):
    """(4) q2 of the segment x -> o by the midpoint rule with Q2_SAMPLES samples."""
    acc = 0.0
    y = np.empty(3)
    for s in range(Q2_SAMPLES):
        t = (s + 0.5) / Q2_SAMPLES
        for k in range(3):
            y[k] = x[k] + t * (o[k] - x[k])
        acc += 1.0 / (1.0 + g_sum(y, origin, cell, dims, cell_start, cell_points, g0v, rc2, cut2, kernel))
    return length * acc / Q2_SAMPLES


def grid_args(fp: FreePoints) -> tuple:
    """The arguments of q2_kernel / g_sum after (x, o, length)."""
    return (fp.origin, fp.cell, fp.dims, fp.cell_start, fp.cell_points, g0(fp.kt), fp.rc * fp.rc,
            fp.cutoff * fp.cutoff, fp.kernel_code)


def q2_many(fp: FreePoints, x: NDArray[np.float64], o: NDArray[np.float64]) -> NDArray[np.float64]:
    """q2 (4) for segments x (S, 3) -> o (S, 3) through the grid (the field kernel's version)."""
    x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
    o = np.asarray(o, dtype=np.float64).reshape(-1, 3)
    L = np.linalg.norm(o - x, axis=1)
    if len(fp.points) == 0:
        return L
    ga = grid_args(fp)
    return np.array([q2_kernel(x[i], o[i], L[i], *ga) for i in range(len(x))])


def praf_potential(fp: FreePoints, x: NDArray[np.float64]) -> NDArray[np.float64]:
    """PRAF potential Psi_P(X) = sum_i G(|X - P_i|) at points x (N, 3) (cKDTree)."""
    x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
    if len(fp.points) == 0:
        return np.zeros(len(x))
    near = fp.tree.query_ball_point(x, fp.cutoff)
    return np.array([free_point_g(np.linalg.norm(fp.points[idx] - xi, axis=1), fp.kt, fp.rc, fp.kernel).sum()
                     if idx else 0.0 for xi, idx in zip(x, near)])


def praf_normal(fp: FreePoints, x: NDArray[np.float64], *, k: int = 12) -> NDArray[np.float64] | None:
    """PRAF normal at one point: the smallest principal axis of the k free points nearest x,
    weighted by G (spec §8 choice). None when fewer than 3 free points lie within the cutoff."""
    if len(fp.points) < 3:
        return None
    dist, idx = fp.tree.query(np.asarray(x, dtype=np.float64), k=min(k, len(fp.points)),
                              distance_upper_bound=fp.cutoff)
    ok = np.isfinite(dist)
    if ok.sum() < 3:
        return None
    p = fp.points[idx[ok]]
    w = free_point_g(dist[ok], fp.kt, fp.rc, fp.kernel)
    c = (w[:, None] * p).sum(axis=0) / w.sum()
    q = p - c
    cov = (w[:, None, None] * q[:, :, None] * q[:, None, :]).sum(axis=0)
    _, vec = np.linalg.eigh(cov)
    return vec[:, 0]

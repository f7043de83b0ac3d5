"""Free points: the effective length q2 (eq. 4) and the point-cloud field PRAF (spec §8).

Each free point P_i is the source of G(R) = k_t/(1-k_t) * kernel(R / R_c) (quality.free_point_g).
Two lookups of the free points near a place:
- a scipy cKDTree (``FreePoints.tree``) for the reference q2 of one bridge (quality.q2_segment)
  and for PRAF's normals;
- a uniform grid (cell = the G cutoff) with flat cell lists: the exact sum of G near a point
  in numba (``g_sum``, ``q2_kernel``);
- a lattice of sum G sampled every R_c / 2 (``lattice``), read by trilinear interpolation in the
  field kernel, which needs q2 for millions of point x source segments (choice: 16 samples per
  segment, O(1) each; the interpolation error is a few per cent of G at most, tested against
  the exact sum).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .quality import free_point_g, g0, g_cutoff

MAX_CELLS = 2_000_000
MAX_LATTICE = 4_000_000  # nodes of the sum-G lattice (its spacing grows beyond R_c / 2 if needed)
Q2_SAMPLES = 8  # midpoint-rule samples along a segment (exact grid version)
LATTICE_SAMPLES = 16  # midpoint-rule samples along a segment in the field kernel


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
    lat_origin: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    lat_spacing: float = 1.0
    lat_dims: NDArray[np.int64] = field(default_factory=lambda: np.ones(3, dtype=np.int64))
    lattice: NDArray[np.float64] = field(default_factory=lambda: np.zeros(1))  # (X*Y*Z,) sum G at the nodes

    @property
    def kernel_code(self) -> int:
        return 0 if self.kernel == "gauss" else 1


def free_points(points: NDArray[np.float64], *, kt: float, rc: float, kernel: str = "gauss") -> FreePoints:
    if not (np.isfinite(rc) and rc > 0):
        raise ValueError(f"free points: the radius r_c must be a positive number, got {rc!r}")
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
    dist = np.asarray(dist).reshape(len(p), k)  # k = 1 (a single free point) gives a flat array
    dist = np.where(np.isfinite(dist), dist, np.inf)
    gs = free_point_g(dist, kt, rc, kernel).sum(axis=1)
    gmax = 1.25 * float(gs.max()) + g0(kt) * 1e-4 * len(p)
    spacing = rc / 2
    while True:
        ldims = np.floor((hi - lo) / spacing).astype(np.int64) + 2
        if int(np.prod(ldims)) <= MAX_LATTICE:
            break
        spacing *= 1.25
    lat = np.zeros(int(np.prod(ldims)))
    _fill_lattice(p, lo, spacing, ldims, lat, g0(kt), rc * rc, cut * cut, 0 if kernel == "gauss" else 1)
    return FreePoints(p, kt, rc, kernel, cut, lo, float(cell), dims, start, np.ascontiguousarray(p[order]), gmax, tree,
                      lo, float(spacing), ldims, lat)


@numba.njit(cache=True)
def _fill_lattice(p, origin, h, dims, lat, g0v, rc2, cut2, kernel):
    """sum_i G(|node - P_i|) at every lattice node within the cutoff of some free point."""
    reach = int(np.ceil(np.sqrt(cut2) / h))
    for i in range(p.shape[0]):
        c0 = int((p[i, 0] - origin[0]) / h)
        c1 = int((p[i, 1] - origin[1]) / h)
        c2 = int((p[i, 2] - origin[2]) / h)
        for a in range(max(c0 - reach, 0), min(c0 + reach + 2, dims[0])):
            dx = origin[0] + a * h - p[i, 0]
            for b in range(max(c1 - reach, 0), min(c1 + reach + 2, dims[1])):
                dy = origin[1] + b * h - p[i, 1]
                for c in range(max(c2 - reach, 0), min(c2 + reach + 2, dims[2])):
                    dz = origin[2] + c * h - p[i, 2]
                    r2 = dx * dx + dy * dy + dz * dz
                    if r2 < cut2:
                        g = g0v * np.exp(-r2 / rc2) if kernel == 0 else g0v / (1.0 + r2 / rc2)
                        lat[(a * dims[1] + b) * dims[2] + c] += g


@numba.njit(cache=True, fastmath=True, inline="always")
def _lattice_at(f0, f1, f2, dims, lat):
    """sum G by trilinear interpolation at lattice coordinates (f0, f1, f2) (0 outside the lattice)."""
    if f0 < 0 or f1 < 0 or f2 < 0 or f0 >= dims[0] - 1 or f1 >= dims[1] - 1 or f2 >= dims[2] - 1:
        return 0.0
    a, b, c = int(f0), int(f1), int(f2)
    u, v, w = f0 - a, f1 - b, f2 - c
    s1, s2 = dims[2], dims[1] * dims[2]
    k = (a * dims[1] + b) * dims[2] + c
    c00 = lat[k] * (1 - u) + lat[k + s2] * u
    c01 = lat[k + 1] * (1 - u) + lat[k + s2 + 1] * u
    c10 = lat[k + s1] * (1 - u) + lat[k + s2 + s1] * u
    c11 = lat[k + s1 + 1] * (1 - u) + lat[k + s2 + s1 + 1] * u
    return (c00 * (1 - v) + c10 * v) * (1 - w) + (c01 * (1 - v) + c11 * v) * w


@numba.njit(cache=True, fastmath=True)
def lattice_g(y, origin, h, dims, lat):
    """sum G at y by trilinear interpolation of the lattice (0 outside it)."""
    return _lattice_at((y[0] - origin[0]) / h, (y[1] - origin[1]) / h, (y[2] - origin[2]) / h, dims, lat)


@numba.njit(cache=True, fastmath=True)
def q2_lattice(x, o, length, origin, h, dims, lat):
    """(4) q2 of the segment x -> o: midpoint rule with LATTICE_SAMPLES samples of the lattice.
    The samples are stepped in lattice coordinates (no division or temporary array per sample)."""
    return q2_lattice_capped(x, o, length, origin, h, dims, lat, 1e300)


@numba.njit(cache=True, fastmath=True)
def q2_lattice_capped(x, o, length, origin, h, dims, lat, cap):
    """q2_lattice, but it may stop as soon as the partial sum already exceeds cap (every term of
    the midpoint rule is positive, so q2 > cap is then certain): the pruning test of the field
    kernel needs no more. Below cap the value is exactly q2_lattice's. cap must be finite
    (fastmath assumes no infinities)."""
    ih = 1.0 / h
    a0, a1, a2 = (x[0] - origin[0]) * ih, (x[1] - origin[1]) * ih, (x[2] - origin[2]) * ih
    g0_, g1, g2 = (o[0] - x[0]) * ih, (o[1] - x[1]) * ih, (o[2] - x[2]) * ih
    acc = 0.0
    cap_n = cap * LATTICE_SAMPLES
    for s in range(LATTICE_SAMPLES):
        t = (s + 0.5) / LATTICE_SAMPLES
        acc += 1.0 / (1.0 + _lattice_at(a0 + t * g0_, a1 + t * g1, a2 + t * g2, dims, lat))
        if acc * length > cap_n:
            break
    return length * acc / LATTICE_SAMPLES


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


def lattice_args(fp: FreePoints) -> tuple:
    """The arguments of q2_lattice after (x, o, length)."""
    return (fp.lat_origin, fp.lat_spacing, fp.lat_dims, fp.lattice)


def q2_many(fp: FreePoints, x: NDArray[np.float64], o: NDArray[np.float64], *, exact: bool = False
            ) -> NDArray[np.float64]:
    """q2 (4) for segments x (S, 3) -> o (S, 3): the lattice (the field kernel's version) or,
    with exact=True, the exact sum of G through the grid (Q2_SAMPLES samples)."""
    x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
    o = np.asarray(o, dtype=np.float64).reshape(-1, 3)
    L = np.linalg.norm(o - x, axis=1)
    if len(fp.points) == 0:
        return L
    if exact:
        ga = grid_args(fp)
        return np.array([q2_kernel(x[i], o[i], L[i], *ga) for i in range(len(x))])
    la = lattice_args(fp)
    return np.array([q2_lattice(x[i], o[i], L[i], *la) for i in range(len(x))])


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

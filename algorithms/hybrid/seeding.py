"""Seeding Stage III along lines of curvature (choice, not in the paper).

The chordal error of a triangle on a surface curved in one direction only (a cone, a cylinder: both
paper surfaces are developable) is set by the triangle's extent across the rulings: an edge of
length h at an angle φ to the curved direction deviates by κ (h cos φ)² / 8. Refinement at
circumcentres leaves triangles in every orientation, so the worst of them puts an edge straight
across (cos φ = 1). A triangle with one edge along the straight direction has its other edges at
30° to the curved one: 3/4 of the worst error at the same size (so 3/4 the triangles at the same
error).

When the parameter lines are lines of curvature (the first and second fundamental forms diagonal:
R_u · R_v = 0 and R_uv · N = 0, as on the cone, the cylinder and every surface of revolution) and
the curvature across one family (the columns) varies only along them, we lay near-equilateral
triangles with one edge along the flatter family: columns of points along that parameter, spaced
h(t) along the column (from the chordal tolerance: 3/4 κ h² / 8 = fill × max_deviation, κ the
curvature across the columns), columns √3/2 h apart, every other column shifted half a step. The
points inside the trim and not within one spacing of the border curve are inserted before Stage III
(Delaunay insertion with the refinement's own flip test, skipped where one would encroach a border
edge); Ruppert refinement then mends what the seeding did not settle, so every bound and the angle
guarantee stand as before.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .model import HybridModel

FILL = 0.9  # the seeded triangles' chordal error as a share of max_deviation
BASE_ANGLE = 54.0  # degrees: the seeded triangles' angles at their edge along a column (their smallest)
ORTHO_TOL = 1e-3  # |cos| of the angle between R_u and R_v, |M| / sqrt(|L N|): "lines of curvature"
SPREAD_TOL = 0.1  # relative spread of the cross curvature across a column's coordinate
FLAT_TOL = 0.02  # the curvature along the columns at most this share of the curvature across them


def _forms(surface, u: NDArray[np.float64], v: NDArray[np.float64]):
    """R_u, R_v, the unit normal and the second fundamental form L, M, N by central differences."""
    a, b, c, d = surface.domain
    hu, hv = 1e-4 * (b - a), 1e-4 * (d - c)
    R = surface(u, v)
    Rp, Rm = surface(u + hu, v), surface(u - hu, v)
    Sp, Sm = surface(u, v + hv), surface(u, v - hv)
    ru, rv = (Rp - Rm) / (2 * hu), (Sp - Sm) / (2 * hv)
    ruu, rvv = (Rp - 2 * R + Rm) / hu ** 2, (Sp - 2 * R + Sm) / hv ** 2
    ruv = (surface(u + hu, v + hv) - surface(u + hu, v - hv) - surface(u - hu, v + hv)
           + surface(u - hu, v - hv)) / (4 * hu * hv)
    n = np.cross(ru, rv)
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
    return ru, rv, n, (ruu * n).sum(-1), (ruv * n).sum(-1), (rvv * n).sum(-1)


def principal_lattice(model: HybridModel, max_deviation: float, *, fill: float = FILL,
                      base_angle: float = BASE_ANGLE, max_edge: float | None = None,
                      samples: int = 25) -> tuple[NDArray[np.float64], float]:
    """(K, 2) parameter points of the aligned lattice inside the parameter rectangle (not yet filtered
    by the trim), and the largest column spacing in space; (0, 2) when the surface does not qualify."""
    s = model.surface
    a, b, c, d = s.domain
    # interior samples (central differences stay inside the rectangle)
    uu, vv = np.meshgrid(np.linspace(a, b, samples + 2)[1:-1], np.linspace(c, d, samples + 2)[1:-1], indexing="ij")
    ru, rv, _n, L, M, N = _forms(s, uu, vv)
    eu, ev = np.linalg.norm(ru, axis=-1), np.linalg.norm(rv, axis=-1)
    ku, kv = np.abs(L) / eu ** 2, np.abs(N) / ev ** 2  # normal curvatures along u and along v
    scale = np.maximum(np.maximum(ku, kv), 1e-300)
    if not np.isfinite([ku, kv]).all() or scale.max() <= 0:
        return np.zeros((0, 2)), 0.0
    ortho = np.abs((ru * rv).sum(-1)) / (eu * ev)
    twist = np.abs(M) / (eu * ev) / scale
    if ortho.max() > ORTHO_TOL or twist.max() > ORTHO_TOL:
        return np.zeros((0, 2)), 0.0  # the parameter lines are not lines of curvature
    along_u = ku.mean() <= kv.mean()  # the columns follow the flatter family
    kx, kt = (kv, ku) if along_u else (ku.T, kv.T)  # across and along the columns; rows: column coordinate t
    if kx.min() <= 0 or kt.max() > FLAT_TOL * kx.min():
        return np.zeros((0, 2)), 0.0  # the columns must be straight lines (rulings) on a curved surface
    if (kx.max(axis=1) - kx.min(axis=1) > SPREAD_TOL * kx.mean(axis=1)).any():
        return np.zeros((0, 2)), 0.0
    (t0, t1), (c0, c1) = ((a, b), (c, d)) if along_u else ((c, d), (a, b))
    periodic = s.periodic_v if along_u else s.periodic_u
    ts = np.linspace(t0, t1, samples + 2)[1:-1]
    cm = 0.5 * (c0 + c1)
    pu, pv = (ts, np.full_like(ts, cm)) if along_u else (np.full_like(ts, cm), ts)
    ru1, rv1 = s.derivatives(pu, pv)
    speed_t = np.linalg.norm(ru1 if along_u else rv1, axis=-1)  # |dR/dt|
    speed_c = np.linalg.norm(rv1 if along_u else ru1, axis=-1)  # |dR/dc|
    # the columns: the error of a triangle is set by its extent w across them, kappa w^2 / 8 at the
    # slanted edges' midpoints (kappa w^2 / 9 at the centroid): w = sqrt(fill 8 max_deviation / kappa),
    # the column step in c the smallest one over the columns' length (no triangle over the tolerance)
    w_t = np.sqrt(fill * 8.0 * max_deviation / kx.max(axis=1))
    if max_edge is not None:  # the longest lattice edge (the column edge, or a slanted one) within it
        cot = 1.0 / math.tan(math.radians(base_angle))
        w_t = np.minimum(w_t, max_edge / max(2.0 * cot, math.sqrt(1.0 + cot * cot)))
    dc = float((w_t / speed_c).min())
    span = c1 - c0
    m = max(2, int(math.ceil(span / dc)))
    if periodic and m % 2:
        m += 1  # the shifted and unshifted columns alternate all the way round
    dc = span / m
    cols = c0 + (np.arange(m) + 0.5) * dc if periodic else c0 + dc * np.arange(1, m)
    # along the columns: isosceles triangles with base angles base_angle on the column edges, so the
    # step is 2 w / tan(base_angle) in arc length (w = dc |dR/dc| the actual extent across)
    step_t = 2.0 * dc * speed_c / math.tan(math.radians(base_angle)) / speed_t
    rows = [t0]
    while True:
        t = rows[-1]
        dt = float(np.interp(t, ts, step_t))
        if t + 0.5 * dt >= t1:
            break
        rows.append(t + dt)
    rows_arr = np.array(rows)
    mids = np.r_[0.5 * (rows_arr[1:] + rows_arr[:-1]), rows_arr[-1] + 0.5 * (t1 - rows_arr[-1])]
    h = float((dc * speed_c).max())
    pts = []
    for j, cj in enumerate(cols):
        tt = mids if j % 2 else rows_arr[1:]
        tt = tt[(tt > t0) & (tt < t1)]
        pts.append(np.stack([tt, np.full_like(tt, cj)], axis=1) if along_u else np.stack([np.full_like(tt, cj), tt], 1))
    P = np.concatenate(pts) if pts else np.zeros((0, 2))
    return P, h


def seed_points(model: HybridModel, lattice: NDArray[np.float64], h: float,
                segments_uv: NDArray[np.float64]) -> NDArray[np.float64]:
    """The points of a lattice (principal_lattice: points, largest column spacing h) inside the trim
    (F > 0) and at least 0.75 h away (in space) from the border segments segments_uv (S, 2, 2)
    (sampled 16 times each); (K, 2) in (u, v)."""
    from scipy.spatial import cKDTree

    if not len(lattice):
        return lattice
    X = model.surface(lattice[:, 0], lattice[:, 1])
    keep = model.F(X) > 0
    if len(segments_uv):
        w = np.linspace(0.0, 1.0, 16)[None, :, None]
        S = segments_uv[:, :1] + w * (segments_uv[:, 1:] - segments_uv[:, :1])  # (S, 16, 2)
        B = model.surface(S[..., 0], S[..., 1]).reshape(-1, 3)
        dist, _ = cKDTree(B).query(X)
        keep &= dist > 0.75 * h
    return lattice[keep]

"""Holes as polygons: their boundary frames and the simple-hole test.

A hole here is a closed walk of vertex indices (mesh loop vertices and bridge chain vertices).
The repair pipeline splits a hole while it is *complex* for the chosen darning method
(spec/repair.md §1: a simple hole is one the darning method fills well). The test is explicit
so the report can say why a hole was split.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from .boundary import LoopFrame, frame_of


@dataclass(frozen=True)
class SimpleHoleTest:
    """Thresholds of the simple-hole test (one set per darning method, see ``for_method``).

    max_vertices: more boundary vertices than this: complex (cost and quality of the fill).
    max_flatness: max distance of the boundary from its best-fit plane, relative to the hole's
        mean radius. A curved or saddle-shaped hole is complex above it.
    min_normal_agreement: mean of n_O . n_plane over the boundary (surface normals against the
        plane's normal, oriented by them): below it the surrounding surface folds over the hole.
    projection_simple: the boundary projected on its plane must not cross itself.
    star_shaped: (fan) every boundary edge must be seen from the centroid counter-clockwise.
    """

    max_vertices: int = 240
    max_flatness: float = 0.45
    min_normal_agreement: float = 0.5
    projection_simple: bool = True
    star_shaped: bool = False

    @classmethod
    def for_method(cls, method: str) -> SimpleHoleTest:
        if method == "fan":
            # the centroid fan only works for nearly flat, star-shaped holes
            return cls(max_vertices=120, max_flatness=0.25, min_normal_agreement=0.7, star_shaped=True)
        if method == "liepa-fair":
            # fairing rebuilds curvature: only folded, tangled or very long holes are complex
            return cls(max_vertices=240, max_flatness=0.8, min_normal_agreement=0.0)
        return cls()  # liepa without fairing: a flat fill, so curved holes are complex

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class HoleVerdict:
    simple: bool
    reasons: tuple[str, ...]
    vertices: int
    flatness: float
    normal_agreement: float
    radius: float

    def as_dict(self) -> dict:
        return asdict(self)


def best_fit_plane(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Centroid and unit normal of the least-squares plane (smallest principal axis)."""
    c = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c, full_matrices=False)
    return c, vt[-1]


def polygon_self_intersects(p2: NDArray[np.float64]) -> bool:
    """Whether a closed 2D polygon (N, 2) has two non-adjacent edges that cross. Vectorised O(N^2)."""
    n = len(p2)
    if n < 4:
        return False
    a = p2
    b = np.roll(p2, -1, axis=0)
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))  # the first and last edges are adjacent
    i, j = i[keep], j[keep]

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    o1 = orient(a[i], b[i], a[j])
    o2 = orient(a[i], b[i], b[j])
    o3 = orient(a[j], b[j], a[i])
    o4 = orient(a[j], b[j], b[i])
    return bool(np.any((o1 * o2 < 0) & (o3 * o4 < 0)))


def classify_hole(points: NDArray[np.float64], normals: NDArray[np.float64],
                  test: SimpleHoleTest) -> HoleVerdict:
    """Apply the simple-hole test to a hole boundary (points (N,3) in walking order, surface
    normals (N,3) at them, zero where unknown)."""
    n = len(points)
    c, nrm = best_fit_plane(points)
    nn = normals[np.linalg.norm(normals, axis=1) > 0]
    if len(nn) and (nn @ nrm).mean() < 0:
        nrm = -nrm
    radius = float(np.linalg.norm(points - c, axis=1).mean())
    flat = float(np.abs((points - c) @ nrm).max() / radius) if radius > 0 else 0.0
    agree = float((nn @ nrm).mean()) if len(nn) else 1.0
    reasons = []
    if n > test.max_vertices:
        reasons.append(f"{n} boundary vertices > {test.max_vertices}")
    if flat > test.max_flatness:
        reasons.append(f"not flat: {flat:.2f} of its radius from its plane > {test.max_flatness}")
    if agree < test.min_normal_agreement:
        reasons.append(f"surface folds over it: normal agreement {agree:.2f} < {test.min_normal_agreement}")
    if test.projection_simple or test.star_shaped:
        u = np.cross(nrm, [1.0, 0, 0] if abs(nrm[0]) < 0.9 else [0, 1.0, 0])
        u /= np.linalg.norm(u)
        w = np.cross(nrm, u)
        p2 = np.stack([(points - c) @ u, (points - c) @ w], axis=1)
        if test.projection_simple and polygon_self_intersects(p2):
            reasons.append("its projection on its plane crosses itself")
        if test.star_shaped:
            q = np.roll(p2, -1, axis=0)
            cross = p2[:, 0] * q[:, 1] - p2[:, 1] * q[:, 0]
            # walking order has the hole on the right: seen from the plane normal, clockwise
            if not (np.all(cross < 0) or np.all(cross > 0)):
                reasons.append("not star-shaped from its centroid")
    return HoleVerdict(not reasons, tuple(reasons), n, flat, agree, radius)


def polygon_frame(vertices: NDArray[np.float64], normals: NDArray[np.float64], polygon: tuple[int, ...] | NDArray,
                  *, island: int = -1, charge: str = "length") -> LoopFrame:
    """Boundary frame (spec §2) of a hole polygon walked with the hole on its right.

    The walk has the surface on its left like a boundary loop in positive direction, so the
    loop formulas apply unchanged (for chain vertices of bridges, n is the force line's normal).
    """
    poly = np.asarray(polygon, dtype=np.int64)
    return frame_of(vertices[poly], normals[poly], poly, island=island, charge=charge)

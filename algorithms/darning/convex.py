"""Fills of holes in locally convex (or locally concave) surroundings, kept inside the planes of
the faces around them.

A convex solid lies on the inner side of the plane of every face of a tessellation inscribed in it,
away from that face (a face's plane is a secant: outside the face's own circumcircle the surface is
below it). So when the input faces around a hole support it (every ring vertex on or below each
face's plane), the missing surface is below every one of those planes too, wherever the shape
stays convex across the hole; to second order this holds for any surface, since a plane tangent at
a ring point that has the whole ring below it has the hole's inside below it as well. A faired
fill that rises above one of them overshoots: the bi-Laplacian continues the tangent planes of
both sides of a soft crease and bulges where they meet (the sweep's frep-boxsphere, a cube cut by
a ball: a fill across the circle where a face meets the ball rose 0.5 % of the diagonal above the
flat face; MeshLib's flat fill 0.02 %). Concave surroundings are the same with the sides swapped.

The faces astride a soft crease do not support the ring (the crease is a curve that a face's
plane cuts across; a cylinder's or cone's faces not along its lines do not either): up to ``STRAY``
of them are left out. A ring with more (a saddle, a scan's noise) is left as it is: on the
peanut's waist, a bound of one half let the clamp sink fills by 0.1 % of the diagonal.

The clamp never lifts a vertex: it only takes back an overshoot beyond the surroundings' planes.
It runs once, on the faired fill before the angle refinement: run again after it, on the points the
refinement moved or inserted, it pressed them into slivers (featuretype, frep-cross, mushroom and
frep-bowl sweep cuts: patch angles of 0.3-2.4 degrees).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..mesh import face_cross

# a ring is convex when no ring vertex lies more than this fraction of the ring's size above the
# plane of a ring face (tessellation rounding; a scan's noise is far above it)
CONVEX_TOL = 1e-4
# ring_planes: at most this share of a ring's faces may fail to support it (the faces astride a soft
# crease: 18 % on frep-boxsphere's holes across the circle where a face meets the ball)
STRAY = 0.25


def ring_planes(V: NDArray[np.float64], ring: NDArray[np.int64], *, tol: float = CONVEX_TOL,
                stray: float | None = None, samples: NDArray[np.float64] | None = None
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The planes (unit normals (K, 3), offsets (K,)) of the faces ``ring`` that support it: every
    ring vertex on or below the plane (within ``tol`` of the ring's extent), the normals pointing
    out of the side the surface bends to, so that the missing surface satisfies ``n . x <= d``
    for each. None when more than ``stray`` (default ``STRAY``) of the faces do not support the
    ring on either side (a saddle, a scan's noise), or when one of ``samples`` (points of the
    missing surface: fill vertices pulled through free points) lies above a plane kept (not convex
    there). Degenerate faces are left out. The faces astride a soft crease do not support the ring
    (the crease is a curve, a face's plane cuts across it): the others do."""
    stray = STRAY if stray is None else stray
    ring = np.asarray(ring, dtype=np.int64)
    if len(ring) < 3:
        return None
    t = V[ring]
    n = face_cross(V, ring)
    area = np.linalg.norm(n, axis=1)
    ok = area > 1e-12 * max(float(area.max()), 1e-300)
    if ok.sum() < 3:
        return None
    n, t = n[ok] / area[ok, None], t[ok]
    d = np.einsum("ij,ij->i", n, t.mean(axis=1))
    pts = np.unique(ring[ok].ravel())
    eps = tol * float(np.linalg.norm(np.ptp(V[pts], axis=0)))
    above = V[pts] @ n.T - d  # (points, faces): signed height over each face's plane
    for sign in (1.0, -1.0):  # convex: the surface below the planes; concave: above them
        support = (sign * above <= eps).all(axis=0)
        if support.mean() >= 1.0 - stray:
            n, d = sign * n[support], sign * d[support]
            if samples is not None and len(samples) and float((samples @ n.T - d).max()) > eps:
                return None
            return n, d
    return None


def clamp_below(X: NDArray[np.float64], normals: NDArray[np.float64], offsets: NDArray[np.float64], *,
                iterations: int = 64) -> NDArray[np.float64]:
    """``X`` (M, 3) moved into the polytope ``normals . x <= offsets``: each point still outside is
    projected onto its most violated plane, in turn, until none is violated (alternating
    projections onto the half-spaces; a point inside does not move)."""
    out = np.array(X, dtype=np.float64, copy=True)
    for _ in range(iterations):
        over = out @ normals.T - offsets  # (M, K)
        k = np.argmax(over, axis=1)
        worst = over[np.arange(len(out)), k]
        bad = worst > 0
        if not bad.any():
            break
        out[bad] -= worst[bad, None] * normals[k[bad]]
    return out


def clamp_fills(V: NDArray[np.float64], F_in: NDArray[np.int64], holes: list[tuple[int, ...]],
                patch_ids: list[NDArray[np.int64]], *, skip: NDArray[np.int64] | None = None,
                held: NDArray[np.int64] | None = None) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The new vertices ``patch_ids[k]`` of each hole ``holes[k]`` (a polygon of vertex ids) whose
    input faces ``F_in`` around it are convex or concave (``ring_planes``), moved back inside those
    faces' planes; returns (positions, the ids that moved). ``skip``: vertices left where they are
    (fitted to an implicit of their own); ``held``: vertices pulled through free points, samples of
    the missing surface: a hole where one of them is outside the planes is not convex there and is
    left as it is."""
    out = V.copy()
    moved: list[NDArray[np.int64]] = []
    skip = np.zeros(0, dtype=np.int64) if skip is None else np.asarray(skip, dtype=np.int64)
    held = np.zeros(0, dtype=np.int64) if held is None else np.asarray(held, dtype=np.int64)
    # the input faces at a hole vertex, found once; each hole's ring among them by a vertex mask
    mask = np.zeros(len(V), dtype=bool)
    for poly in holes:
        mask[list(poly)] = True
    near = F_in[mask[F_in].any(axis=1)]
    mask[:] = False
    for poly, ids in zip(holes, patch_ids):
        ids = np.setdiff1d(ids, skip)
        if not len(ids) or len(poly) < 3:
            continue
        mask[list(poly)] = True
        ring = near[mask[near].any(axis=1)]
        mask[list(poly)] = False
        planes = ring_planes(V, ring, samples=V[ids[np.isin(ids, held)]])
        if planes is None:
            continue
        new = clamp_below(V[ids], *planes)
        step = np.any(new != V[ids], axis=1)
        out[ids[step]] = new[step]
        moved.append(ids[step])
    return out, (np.concatenate(moved) if moved else np.zeros(0, dtype=np.int64))

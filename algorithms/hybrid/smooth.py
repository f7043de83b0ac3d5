"""A finishing pass after Stage III (choice, not in the paper): smart smoothing on the surface.

Each interior vertex is moved towards a target point in space: the 3D mean of its neighbours
(Laplacian), or the area-weighted mean of its triangles' 3D circumcentres (the optimal Delaunay
triangulation update of Chen and Xu, ODT), which evens out triangle shapes where Laplacian smoothing
stalls. The target is found in (u, v)
by Gauss-Newton on |R(u, v) − mean|² (two steps from the vertex's own parameters, the Jacobian by
finite differences), so a non-uniform parameterisation does not pull the vertex off the middle of
its neighbours in space. The move is kept only if every triangle around the vertex stays
counter-clockwise in (u, v), the mean of the triangles' minimum 3D angles around it increases
while their smallest stays above the angle bound (or, where it was below already, does not decrease),
and (when a chordal tolerance is given) the chordal error of its triangles stays within it. So the minimum
angle bound and the chordal bound of the refinement are kept and the median improves. Border
vertices never move (they are on F = 0 or on the sides of P, and the seams stay welded).

Vectorised: the interior vertices are split into independent sets (greedy colouring of the edge
graph: no two vertices of a set share an edge, so no triangle has two of them) and each set is
moved at once, with one surface call per step for the whole set.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .cdt import Triangulation
from .chordal import chordal_errors, gauss_newton_step


def _min_angles(T: NDArray[np.float64]) -> NDArray[np.float64]:
    """(K, 3, 3) triangles → (K,) smallest angle in degrees: the angle opposite the shortest edge, by
    the law of cosines (one arccos per triangle)."""
    e = T[:, [1, 2, 0]] - T  # edges (0→1, 1→2, 2→0)
    L2 = np.einsum("kij,kij->ki", e, e)
    L2.sort(axis=1)
    a2, b2, c2 = L2[:, 0], L2[:, 1], L2[:, 2]
    den = 2.0 * np.sqrt(b2 * c2)
    cos = np.where(den > 0, (b2 + c2 - a2) / np.where(den > 0, den, 1.0), 1.0)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _longest(T: NDArray[np.float64]) -> NDArray[np.float64]:
    """(K, 3, 3) triangles → (K,) longest 3D edge."""
    e = T[:, [1, 2, 0]] - T
    return np.sqrt(np.einsum("kij,kij->ki", e, e).max(axis=1))


def _colours(n: int, edges: NDArray[np.int64], movable: NDArray[np.bool_]) -> list[NDArray[np.int64]]:
    """Greedy colouring of the movable vertices: lists of independent vertex sets."""
    nb: list[list[int]] = [[] for _ in range(n)]
    for a, b in edges.tolist():
        nb[a].append(b)
        nb[b].append(a)
    colour = [-1] * n
    for v in np.flatnonzero(movable).tolist():
        used = {colour[w] for w in nb[v]}
        c = 0
        while c in used:
            c += 1
        colour[v] = c
    col = np.array(colour)
    return [np.flatnonzero(col == c) for c in range(col.max() + 1)] if (col >= 0).any() else []


def smooth(tri: Triangulation, *, passes: int = 2, max_deviation: float | None = None, guard: float = 30.0,
           max_edge: float | None = None, target: str = "laplace", only: NDArray[np.bool_] | None = None) -> int:
    """Returns the number of accepted moves. guard: the angle bound kept (degrees); max_edge: no move
    makes a 3D edge longer than this (or longer than it was, where it was over already); target:
    "laplace" or "odt"; only: (optional mask) the vertices that may move."""
    if target not in ("laplace", "odt"):
        raise ValueError(f"target: 'laplace' or 'odt', got {target!r}")
    faces = tri.faces()
    if not len(faces) or passes <= 0:
        return 0
    n = len(tri.uv)
    uv = np.array(tri.uv, dtype=np.float64)
    p3 = np.array(tri.p3, dtype=np.float64)
    movable = tri.interior_mask(faces, only)
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    key = np.unique(e[:, 0] * n + e[:, 1])  # the edges, once each
    edges = np.stack([key // n, key % n], axis=1)
    deg = np.bincount(edges.ravel(), minlength=n).astype(np.float64)
    # incidence: for each (triangle, corner) pair, sorted by vertex
    tri_of = np.repeat(np.arange(len(faces)), 3)
    corner = np.tile(np.arange(3), len(faces))
    vert = faces.ravel()
    sets = _colours(n, edges, movable)
    a, b, c, d = tri.domain
    hu, hv = 1e-7 * (b - a), 1e-7 * (d - c)
    surf = tri.surface
    accepted = 0
    for _ in range(passes):
        for vs in sets:
            if not len(vs):
                continue
            # the triangles around the set, before the move
            sel = np.isin(vert, vs)
            ft, fc, fv = tri_of[sel], corner[sel], vert[sel]
            pos = np.searchsorted(vs, fv)  # vs is sorted (flatnonzero)
            F = faces[ft]
            T3o, T2o = p3[F], uv[F]
            if target == "odt":  # the area-weighted mean of the fan's 3D circumcentres
                A, B, C = T3o[:, 0], T3o[:, 1], T3o[:, 2]
                ea, eb = A - C, B - C
                nrm = np.cross(ea, eb)
                n2 = np.maximum((nrm * nrm).sum(1), 1e-300)
                la, lb = (ea * ea).sum(1)[:, None], (eb * eb).sum(1)[:, None]
                cc = C + np.cross(la * eb - lb * ea, nrm) / (2 * n2[:, None])
                w = np.sqrt(n2)
                goal = np.zeros((len(vs), 3))
                np.add.at(goal, pos, w[:, None] * cc)
                goal /= np.maximum(np.bincount(pos, w, minlength=len(vs)), 1e-300)[:, None]
            else:  # the 3D mean of the neighbours
                s3 = np.zeros((n, 3))
                np.add.at(s3, edges[:, 0], p3[edges[:, 1]])
                np.add.at(s3, edges[:, 1], p3[edges[:, 0]])
                goal = s3[vs] / deg[vs, None]
            x = uv[vs].copy()
            R = p3[vs].copy()
            for _step in range(2):  # Gauss-Newton on |R(u, v) − goal|²
                q = surf(np.r_[x[:, 0] + hu, x[:, 0]], np.r_[x[:, 1], x[:, 1] + hv])
                ru, rv = (q[:len(x)] - R) / hu, (q[len(x):] - R) / hv
                x = x + np.stack(gauss_newton_step(ru, rv, goal - R), axis=1)
                x[:, 0] = np.clip(x[:, 0], a, b)
                x[:, 1] = np.clip(x[:, 1], c, d)
                R = surf(x[:, 0], x[:, 1])
            T3n, T2n = T3o.copy(), T2o.copy()
            rows = np.arange(len(F))
            T3n[rows, fc] = R[pos]
            T2n[rows, fc] = x[pos]
            area = ((T2n[:, 1, 0] - T2n[:, 0, 0]) * (T2n[:, 2, 1] - T2n[:, 0, 1])
                    - (T2n[:, 1, 1] - T2n[:, 0, 1]) * (T2n[:, 2, 0] - T2n[:, 0, 0]))
            scale = np.abs(T2o[:, 1] - T2o[:, 0]).sum(1) + np.abs(T2o[:, 2] - T2o[:, 0]).sum(1)
            good = area > 1e-12 * scale * scale
            mo, mn = _min_angles(T3o), np.where(good, _min_angles(T3n), -1.0)
            old_min = np.full(len(vs), np.inf)
            new_min = np.full(len(vs), np.inf)
            np.minimum.at(old_min, pos, mo)
            np.minimum.at(new_min, pos, mn)
            cnt = np.bincount(pos, minlength=len(vs))
            old_mean = np.bincount(pos, mo, minlength=len(vs)) / np.maximum(cnt, 1)
            new_mean = np.bincount(pos, mn, minlength=len(vs)) / np.maximum(cnt, 1)
            # the fan's smallest angle may not fall below the bound (nor below its old value if it was
            # under it already), and its mean minimum angle must improve
            accept = (new_min >= np.minimum(old_min, guard)) & (new_mean > old_mean)
            if max_edge is not None:
                lo, ln = _longest(T3o), _longest(T3n)
                old_l, new_l = np.zeros(len(vs)), np.zeros(len(vs))
                np.maximum.at(old_l, pos, lo)
                np.maximum.at(new_l, pos, ln)
                accept &= new_l <= np.maximum(max_edge, old_l)
            if max_deviation is not None and accept.any():
                # the fans' chordal errors after the move; before it only where they exceed the tolerance
                fsel = accept[pos]
                worst_new = np.zeros(len(vs))
                np.maximum.at(worst_new, pos[fsel], chordal_errors(surf, T3n[fsel], T2n[fsel]))
                over = accept & (worst_new > max_deviation)
                if over.any():
                    fo = over[pos]
                    worst_old = np.zeros(len(vs))
                    np.maximum.at(worst_old, pos[fo], chordal_errors(surf, T3o[fo], T2o[fo]))
                    accept &= ~over | (worst_new <= worst_old)
            mv = vs[accept]
            uv[mv] = x[accept]
            p3[mv] = R[accept]
            accepted += int(accept.sum())
    for v in np.flatnonzero(movable).tolist():
        tri.uv[v] = (float(uv[v, 0]), float(uv[v, 1]))
        tri.p3[v] = (float(p3[v, 0]), float(p3[v, 1]), float(p3[v, 2]))
    return accepted

"""Minimum-weight triangulation of a hole polygon (Liepa 2003; spec/frep.md §4 "Filling").

The hole polygon v_0 ... v_{n-1} (a closed loop in 3-D) is triangulated by dynamic programming:

    W_{i,i+1} = 0
    W_{i,k}   = min_{i<m<k}  W_{i,m} + W_{m,k} + weight(v_i, v_m, v_k)        (frep.md §4)

remembering the argmin M_{i,k}, then the faces are rebuilt from M starting at (0, n-1). The DP
runs over the diagonals d = k - i (a sequential dependency: W on diagonal d needs all shorter
diagonals); on one diagonal every (i, k) and every m are computed at once with numpy, so the
Python loop has n iterations and the work is the O(n^3) of the method in vectorised form.

Weights: ``"area"`` (triangle area, the minimal-area patch), ``"length"`` (the triangle's
perimeter: summed over a triangulation it is twice the interior edge length plus the fixed loop
length, so this is the minimum total edge length), and ``"dihedral"``: Liepa's weight, the pair
(largest dihedral angle between adjacent triangles, including the surrounding faces across the
loop edges; total area), compared lexicographically (max for the angle, sum for the area).

Chords that already are edges of the surrounding surface can be forbidden (they would become
non-manifold edges); they get an infinite weight.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from ..topology import face_adjacency

WEIGHTS = ("area", "length", "dihedral")
_ANGLE_TOL = 1e-6  # radians: max-angles closer than this are ties, the area decides (Liepa's lexicographic order)
# a triangle (v_i, v_m, v_k) has no area when sin of its angle at v_i is at most this: |(v_m - v_i) x (v_k - v_i)|
# <= NO_AREA |v_m - v_i| |v_k - v_i| (three collinear or coincident loop points)
NO_AREA = 1e-6


def _tri_weight(a: NDArray, b: NDArray, c: NDArray, weight: str) -> NDArray:
    if weight == "length":
        return (np.linalg.norm(b - a, axis=-1) + np.linalg.norm(c - b, axis=-1) + np.linalg.norm(a - c, axis=-1))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=-1)


def _angle(n1: NDArray, n2: NDArray) -> NDArray:
    """Angle between (unnormalised) normals; 0 where one of them is degenerate."""
    c = np.linalg.norm(np.cross(n1, n2), axis=-1)
    d = np.einsum("...j,...j->...", n1, n2)
    return np.arctan2(c, d)


def triangulate(points: NDArray[np.float64], *, weight: str = "area",
                forbidden: NDArray[np.bool_] | None = None,
                outside_normals: NDArray[np.float64] | None = None) -> NDArray[np.int64] | None:
    """Minimum-weight triangulation of a closed polygon; None when every triangulation uses a
    ``forbidden`` chord (the caller decides what then: darn fans the loop from its centroid, whose
    faces have no chord).

    points: (n, 3) the loop, n >= 3, in the loop's positive direction (the surrounding surface
        has half-edge v_j -> v_{j+1}).
    weight: one of ``WEIGHTS``.
    forbidden: optional (n, n) bool, True for chords (i, k) that must not be used.
    outside_normals: (n, 3) for ``"dihedral"``: the normal of the surrounding face across loop
        edge j = (v_j, v_{j+1 mod n}); without it the loop edges add no angle term.

    Returns (n-2, 3) local vertex indices, wound so that each face holds the loop edges reversed
    (v_{j+1} -> v_j), i.e. consistently oriented with the surrounding surface.
    """
    if weight not in WEIGHTS:
        raise ValueError(f"weight must be one of {WEIGHTS}, got {weight!r}")
    p = np.asarray(points, dtype=np.float64)
    n = len(p)
    if n < 3:
        raise ValueError(f"a hole needs at least 3 vertices, got {n}")
    if forbidden is not None:
        forbidden = np.asarray(forbidden, dtype=bool)
        if forbidden.shape != (n, n):
            raise ValueError(f"forbidden must be ({n}, {n}), got {forbidden.shape}")
    if weight != "dihedral":
        W00, M = _dp_fast(p, weight, forbidden)
    else:
        W00, M = _dp_dihedral(p, forbidden, outside_normals)
    if not np.isfinite(W00):
        if forbidden is not None and forbidden.any():
            return None  # every triangulation uses a forbidden chord
        raise ValueError("no finite-weight triangulation (non-finite coordinates?)")
    return _rebuild(M, n)


def max_dihedral(points: NDArray[np.float64], faces: NDArray[np.int64],
                 outside_normals: NDArray[np.float64] | None = None) -> float:
    """The largest angle (radians) between the normals of two faces of a triangulation of the loop
    ``points`` that share an edge, and, with ``outside_normals`` (as for ``triangulate``: the
    surrounding face across each loop edge, zero where there is none), between a face on a loop
    edge and the face beyond it. A face of no area counts as pi. pi means a fold: the fill turns
    back on itself (or on the surface around it)."""
    p = np.asarray(points, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    n = len(p)
    nt = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
    scale = np.linalg.norm(p[f[:, 1]] - p[f[:, 0]], axis=1) * np.linalg.norm(p[f[:, 2]] - p[f[:, 0]], axis=1)
    if (np.linalg.norm(nt, axis=1) <= NO_AREA * scale).any():
        return float(np.pi)
    pairs = face_adjacency(f)  # the faces on each interior edge
    worst = float(_angle(nt[pairs[:, 0]], nt[pairs[:, 1]]).max()) if len(pairs) else 0.0
    if outside_normals is not None:
        nb = np.asarray(outside_normals, dtype=np.float64)
        he = np.stack([f, np.roll(f, -1, axis=1)], axis=2).reshape(-1, 2)  # face t's half-edges at 3t .. 3t+2
        face = np.repeat(np.arange(len(f)), 3)
        # loop edge j is the patch half-edge (j+1) -> j
        on_loop = (he[:, 0] - he[:, 1]) % n == 1
        j = he[on_loop, 1]
        has = np.linalg.norm(nb[j], axis=1) > 0
        if has.any():
            worst = max(worst, float(_angle(nt[face[on_loop]][has], nb[j][has]).max()))
    return worst


def _rebuild(M: NDArray[np.int64], n: int) -> NDArray[np.int64]:
    """Faces from the argmin table, wound against the loop (patch side)."""
    out = np.empty((n - 2, 3), dtype=np.int64)
    stack = [(0, n - 1)]
    t = 0
    while stack:  # sequential: a walk down the DP's recursion tree
        i, k = stack.pop()
        if k - i < 2:
            continue
        m = int(M[i, k])
        out[t] = (k, m, i)  # loop order (i, m, k) reversed
        t += 1
        stack.append((i, m))
        stack.append((m, k))
    return out


def triangulation_weight(points: NDArray[np.float64], faces: NDArray[np.int64], *, weight: str = "area") -> float:
    """Total weight (area or perimeter sum) of a triangulation of the polygon; for tests and reports."""
    p = np.asarray(points, dtype=np.float64)
    f = np.asarray(faces)
    return float(_tri_weight(p[f[:, 0]], p[f[:, 1]], p[f[:, 2]], weight).sum())


def _dp_fast(p: NDArray[np.float64], weight: str,
             forbidden: NDArray[np.bool_] | None) -> tuple[float, NDArray[np.int64]]:
    """The DP for the area and length weights, on skewed tables so that every gather is a slice.

    S[i, j] = W_{i, i+j} and T[k, j] = W_{k-j, k}: for the diagonal d and row i (k = i + d) the
    candidates m = i + j, j = 1..d-1, read W_{i,m} = S[i, j] (a row slice) and
    W_{m,k} = T[k, d-j] (a reversed row slice). The triangle weight comes from tables of the same
    layout: edge lengths, or pairwise cross products C_{a,b} = v_a x v_b with
    (v_m - v_i) x (v_k - v_i) = C_{i,m} + C_{m,k} - C_{i,k} (coordinates centred first).
    """
    n = len(p)
    q = p - p.mean(axis=0)
    r = np.arange(n)
    fwd = (r[:, None] + r[None, :]) % n  # fwd[i, j] = i + j
    bwd = (r[:, None] - r[None, :]) % n  # bwd[k, j] = k - j
    if weight == "length":
        DS = np.linalg.norm(q[:, None, :] - q[fwd], axis=2)  # |v_i - v_{i+j}|
        DT = DS[bwd, r[None, :]]  # |v_{k-j} - v_k|
    else:
        # one (n, n) table per coordinate keeps the row slices contiguous
        CS = np.moveaxis(np.cross(q[:, None, :], q[fwd]), 2, 0).copy()  # v_i x v_{i+j}
        CT = np.moveaxis(np.cross(q[bwd], q[:, None, :]), 2, 0).copy()  # v_{k-j} x v_k
    S = np.full((n, n), np.inf)
    T = np.full((n, n), np.inf)
    S[:, 1] = 0.0
    T[:, 1] = 0.0
    M = np.full((n, n), -1, dtype=np.int64)
    if weight == "length":
        CS = CT = np.zeros((3, 0, 0))
    else:
        # a triangle of three collinear (or coincident) loop points has area 0, so the area weight
        # would prefer it (CAD borders have runs of collinear vertices): it costs `pen`, more than
        # any whole patch, so it is used only when no triangulation avoids it (never for a simple
        # planar polygon)
        DS = np.sum((q[:, None, :] - q[fwd]) ** 2, axis=2)  # |v_i - v_{i+j}|^2
        DT = DS[bwd, r[None, :]]
    pen = 1e6 * float(np.sum(np.ptp(q, axis=0) ** 2))
    fb = np.zeros((0, 0), dtype=np.bool_) if forbidden is None else np.ascontiguousarray(forbidden, dtype=np.bool_)
    _dp_diagonals(CS, CT, DS, DT, weight == "length", fb, forbidden is not None, S, T, M, pen)
    return float(S[0, n - 1]), M


@numba.njit(cache=True)
def _dp_diagonals(CS, CT, DS, DT, length, forbidden, has_forbidden, S, T, M, pen):  # pragma: no cover - compiled
    """The diagonals of _dp_fast, compiled: for diagonal d and row i (k = i + d), the candidate
    m = i + j (j = 1..d-1) costs S[i, j] + T[k, d-j] + the triangle (i, m, k)'s weight, summed in
    the order the vectorised form used; the first minimum wins (np.argmin's rule)."""
    n = S.shape[0]
    for d in range(2, n):  # sequential: diagonal d needs every shorter diagonal
        for i in range(n - d):
            k = i + d
            best = np.inf
            bj = 0
            for j in range(1, d):
                c = S[i, j] + T[k, d - j]
                if length:
                    c = c + DS[i, j] + DT[k, d - j] + DS[i, d]
                else:
                    sq = 0.0
                    for a in range(3):  # the three coordinates of (v_m - v_i) x (v_k - v_i)
                        nc = CS[a, i, j] + CT[a, k, d - j] - CS[a, i, d]
                        sq += nc * nc
                    c = c + 0.5 * np.sqrt(sq)
                    # |(v_m - v_i) x (v_k - v_i)| = |v_m - v_i| |v_k - v_i| sin(angle at v_i): zero
                    # (to NO_AREA relative) exactly when the triangle is degenerate
                    if sq <= NO_AREA * NO_AREA * DS[i, j] * DS[i, d]:
                        c = c + pen
                if c < best:
                    best = c
                    bj = j - 1
            if has_forbidden and d < n - 1 and forbidden[i, k]:
                best = np.inf
            S[i, d] = best
            T[k, d] = best
            M[i, k] = i + 1 + bj


def _dp_dihedral(p: NDArray[np.float64], forbidden: NDArray[np.bool_] | None,
                 outside_normals: NDArray[np.float64] | None) -> tuple[float, NDArray[np.int64]]:
    """Liepa's weight: (max dihedral angle, area) compared lexicographically; max over the angle
    terms, sum over the areas. The dihedral angle of the candidate triangle (i, m, k) is taken
    against the triangles already chosen for the sub-polygons (i, m) and (m, k), or against the
    surrounding face across a loop edge."""
    n = len(p)
    W = np.full((n, n), np.inf)
    A = np.full((n, n), np.inf)  # max dihedral angle inside the sub-polygon i..k
    M = np.full((n, n), -1, dtype=np.int64)
    idx = np.arange(n - 1)
    W[idx, idx + 1] = 0.0
    A[idx, idx + 1] = 0.0
    # neighbour normal across loop edge (j, j+1) in the DP's loop-order convention (triangle
    # (i, m, k), i<m<k, has normal (v_m - v_i) x (v_k - v_i), the reverse of the patch face's):
    # the surrounding face's normal, negated.
    nb = np.zeros((0, 3)) if outside_normals is None else -np.ascontiguousarray(outside_normals, dtype=np.float64)
    fb = np.zeros((0, 0), dtype=np.bool_) if forbidden is None else np.ascontiguousarray(forbidden, dtype=np.bool_)
    _dihedral_diagonals(np.ascontiguousarray(p), nb, outside_normals is not None, fb, forbidden is not None,
                        W, A, M, _ANGLE_TOL)
    return float(W[0, n - 1]), M


@numba.njit(cache=True)
def _angle3(a0, a1, a2, b0, b1, b2):  # pragma: no cover - compiled
    """_angle of two 3-vectors given by their coordinates."""
    c0, c1, c2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    return np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2), a0 * b0 + a1 * b1 + a2 * b2)


@numba.njit(cache=True)
def _dihedral_diagonals(p, nb, has_nb, forbidden, has_forbidden, W, A, M, tol):  # pragma: no cover - compiled
    """The diagonals of _dp_dihedral, compiled. For the sub-polygon (i, k) and each m between: the
    area sum ``cand`` and the largest dihedral angle ``ang`` (of the sub-polygons' own, and of the
    triangle (i, m, k) against the triangle chosen across (i, m) and across (m, k), or against the
    surrounding face across a loop edge, and across the closing loop edge on the last diagonal).
    The smallest angle wins; among angles within ``tol`` of it, the smallest area (the first on ties).
    A degenerate triangle (three collinear points) counts as a fold (pi): with no normal, its angles
    read 0, and the DP strung CAD borders' collinear runs into slivers of no area."""
    n = p.shape[0]
    cand = np.empty(n)
    ang = np.empty(n)
    for d in range(2, n):  # sequential: diagonal d needs every shorter diagonal
        for i in range(n - d):
            k = i + d
            amin = np.inf
            for j in range(1, d):
                m = i + j
                u0, u1, u2 = p[m, 0] - p[i, 0], p[m, 1] - p[i, 1], p[m, 2] - p[i, 2]
                v0, v1, v2 = p[k, 0] - p[i, 0], p[k, 1] - p[i, 1], p[k, 2] - p[i, 2]
                t0, t1, t2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0  # the triangle's normal
                sq = t0 * t0 + t1 * t1 + t2 * t2
                c = W[i, m] + W[m, k] + 0.5 * np.sqrt(sq)
                g = max(A[i, m], A[m, k])
                if sq <= NO_AREA * NO_AREA * (u0 * u0 + u1 * u1 + u2 * u2) * (v0 * v0 + v1 * v1 + v2 * v2):
                    g = np.pi  # three collinear loop points (a CAD border): no normal, as bad as a fold
                q = M[i, m]
                if q >= 0:  # across (i, m): the triangle (i, q, m) chosen for that sub-polygon
                    w0, w1, w2 = p[q, 0] - p[i, 0], p[q, 1] - p[i, 1], p[q, 2] - p[i, 2]
                    g = max(g, _angle3(t0, t1, t2, w1 * u2 - w2 * u1, w2 * u0 - w0 * u2, w0 * u1 - w1 * u0))
                elif has_nb:  # a loop edge: the surrounding face
                    g = max(g, _angle3(t0, t1, t2, nb[i, 0], nb[i, 1], nb[i, 2]))
                q = M[m, k]
                if q >= 0:
                    w0, w1, w2 = p[q, 0] - p[m, 0], p[q, 1] - p[m, 1], p[q, 2] - p[m, 2]
                    z0, z1, z2 = p[k, 0] - p[m, 0], p[k, 1] - p[m, 1], p[k, 2] - p[m, 2]
                    g = max(g, _angle3(t0, t1, t2, w1 * z2 - w2 * z1, w2 * z0 - w0 * z2, w0 * z1 - w1 * z0))
                elif has_nb:
                    g = max(g, _angle3(t0, t1, t2, nb[m, 0], nb[m, 1], nb[m, 2]))
                if d == n - 1 and has_nb:  # the closing loop edge (v_{n-1}, v_0)
                    g = max(g, _angle3(t0, t1, t2, nb[n - 1, 0], nb[n - 1, 1], nb[n - 1, 2]))
                if not np.isfinite(c):
                    g = np.inf
                cand[j] = c
                ang[j] = g
                if g < amin:
                    amin = g
            best = np.inf
            bj = 1
            for j in range(1, d):
                if ang[j] <= amin + tol and cand[j] < best:
                    best = cand[j]
                    bj = j
            W[i, k] = cand[bj]
            A[i, k] = ang[bj]
            M[i, k] = i + bj
            if has_forbidden and d < n - 1 and forbidden[i, k]:
                W[i, k] = np.inf
                A[i, k] = np.inf

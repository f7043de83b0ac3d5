"""Sharp creases that a hole interrupts, and the chains that continue them across the hole.

**(choice)**, not in spec/repair.md: a hole cut across a sharp crease (a CAD edge) is darned as a
smooth patch by §6 step 4, which rounds the crease off. Here the crease is continued first: every
sharp input edge (dihedral angle above ``angle`` degrees) that ends on the hole border gives a
crease end (its border vertex and the crease direction into the hole); two crease ends of one hole
whose directions point at each other are joined by a chain (a cubic Hermite curve with the two
crease directions as its end tangents), which splits the hole like any split bridge. The chain
vertices are then held fixed by the fairing, so each side is faired as its own smooth surface and
the crease stays sharp. Three crease ends whose rays meet at one point (a corner of the part)
are joined through that point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .topology import face_adjacency


@dataclass(frozen=True, eq=False)
class CreaseEnds:
    """Sharp input edges by their vertices: for every vertex, the directions of the sharp edges
    that end there (unit vectors from the other end to the vertex) and those other ends."""

    directions: dict[int, list[NDArray[np.float64]]]
    others: dict[int, list[int]]
    normals: dict[int, list[NDArray[np.float64]]]  # (2, 3): the normals of the edge's two faces

    def at(self, polygon: tuple[int, ...], V: NDArray[np.float64] | None = None,
           along: float = 12.0) -> list[tuple[int, NDArray[np.float64], NDArray[np.float64]]]:
        """(position, direction, face normals) of the crease ends on a hole polygon: sharp edges
        that reach the polygon from outside it (an edge between two polygon vertices runs along
        the border). With ``V``: where the border itself goes on along the crease (the next border
        vertex within ``along`` degrees of the crease direction), the end moves along it, so that
        no chain starts beside a border edge that already continues the crease."""
        on = set(polygon)
        out = [(k, d, n) for k, v in enumerate(polygon)
               for d, w, n in zip(self.directions.get(int(v), ()), self.others.get(int(v), ()),
                                  self.normals.get(int(v), ())) if w not in on]
        if V is None:
            return out
        m, lim = len(polygon), np.cos(np.radians(along))
        moved = []
        for k, d, n in out:
            for _ in range(m):  # sequential: walk while the border follows the crease
                step = [k2 for k2 in ((k + 1) % m, (k - 1) % m)
                        if float(d @ _unit(V[polygon[k2]] - V[polygon[k]])) > lim]
                if not step:
                    break
                k = step[0]
            moved.append((k, d, n))
        return moved

    def use(self, v: int) -> None:
        """A crease end that has been continued: no other chain starts there."""
        self.directions.pop(int(v), None)
        self.others.pop(int(v), None)
        self.normals.pop(int(v), None)


def _unit(a: NDArray[np.float64]) -> NDArray[np.float64]:
    n = float(np.linalg.norm(a))
    return a / n if n > 0 else a


def _shared(n1: NDArray[np.float64], n2: NDArray[np.float64], cos_lim: float) -> int:
    """How many of the two face normals of one crease end match one of the other's (0, 1 or 2)."""
    m = n1 @ n2.T  # (2, 2) cosines
    if m[0, 0] > cos_lim and m[1, 1] > cos_lim or m[0, 1] > cos_lim and m[1, 0] > cos_lim:
        return 2
    return int((m > cos_lim).any())


def sharp_edges(vertices: NDArray[np.float64], faces: NDArray[np.int64],
                angle: float) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """(K, 2) manifold edges whose two faces meet at a dihedral angle above ``angle`` degrees, and
    (K, 2, 3) the unit normals of their two faces."""
    f = np.asarray(faces, dtype=np.int64)
    if not len(f):
        return np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2, 3))
    t = vertices[f]
    fn = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    fn /= np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300)
    pairs = face_adjacency(f)
    cos = np.einsum("ij,ij->i", fn[pairs[:, 0]], fn[pairs[:, 1]])
    sharp = pairs[cos < np.cos(np.radians(angle))]
    a, b = f[sharp[:, 0]], f[sharp[:, 1]]
    common = (a[:, :, None] == b[:, None, :]).any(axis=2)  # the two shared vertices of each pair
    e = a[common].reshape(-1, 2)
    return e, np.stack([fn[sharp[:, 0]], fn[sharp[:, 1]]], axis=1)


def crease_ends(vertices: NDArray[np.float64], faces: NDArray[np.int64], angle: float) -> CreaseEnds:
    out: dict[int, list[NDArray[np.float64]]] = {}
    oth: dict[int, list[int]] = {}
    nrm: dict[int, list[NDArray[np.float64]]] = {}
    edges, fn = sharp_edges(vertices, faces, angle)
    for (a, b), nn in zip(edges.tolist(), fn):
        d = vertices[a] - vertices[b]
        n = float(np.linalg.norm(d))
        if n > 0:
            out.setdefault(a, []).append(d / n)
            out.setdefault(b, []).append(-d / n)
            oth.setdefault(a, []).append(b)
            oth.setdefault(b, []).append(a)
            nrm.setdefault(a, []).append(nn)
            nrm.setdefault(b, []).append(nn)
    return CreaseEnds(out, oth, nrm)


def hermite(p0: NDArray[np.float64], d0: NDArray[np.float64], p1: NDArray[np.float64], d1: NDArray[np.float64],
            spacing: float) -> NDArray[np.float64]:
    """Interior points of the cubic Hermite curve from p0 (tangent d0) to p1 (tangent d1), tangents
    scaled by the chord length, evenly about ``spacing`` apart along the curve; at least one (a
    chain without interior points would be a chord that may already be an edge of the surface)."""
    from .bridge_graph import resample_chain

    L = float(np.linalg.norm(p1 - p0))
    t = np.linspace(0.0, 1.0, 65)[:, None]  # dense, then resampled by arc length
    h00, h10, h01, h11 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t, -2 * t**3 + 3 * t**2, t**3 - t**2
    curve = h00 * p0 + h10 * L * d0 + h01 * p1 + h11 * L * d1
    length = float(np.linalg.norm(np.diff(curve, axis=0), axis=1).sum())
    return resample_chain(curve, min(spacing, length / 2))


@dataclass(frozen=True)
class CreaseSplit:
    """Split a hole polygon at positions i and j by a chain through ``points`` (interior points)."""

    i: int
    j: int
    points: NDArray[np.float64]
    quality: float  # how well the two directions point at each other (2 = exactly)


def _interleaved(a: tuple[int, int], b: tuple[int, int]) -> bool:
    (i, j), (k, m) = sorted(a), sorted(b)
    return (i < k < j) != (i < m < j) and len({i, j, k, m}) == 4


def crease_split(V: NDArray[np.float64], polygon: tuple[int, ...], ends: CreaseEnds, spacing: float, *,
                 max_turn: float = 25.0, max_normal_turn: float = 30.0) -> CreaseSplit | None:
    """The best crease chain across the hole ``polygon``, or None.

    A crease end is a polygon vertex with a sharp input edge ending there; its direction d must
    point into the hole. Ends i and j pair when the chord u from i to j is within ``max_turn``
    degrees of d_i and of -d_j, and the two faces along the crease at i face like the two at j
    (within ``max_normal_turn`` degrees: the same two surfaces meet there); the best pair (largest
    d_i . u - d_j . u) is returned.
    """
    cand = ends.at(polygon, V)
    if len(cand) < 2:
        return None
    lim = np.cos(np.radians(max_turn))
    nlim = np.cos(np.radians(max_normal_turn))
    best = None
    n = len(polygon)
    for x in range(len(cand)):
        for y in range(x + 1, len(cand)):
            (i, di, ni), (j, dj, nj) = cand[x], cand[y]
            if min((i - j) % n, (j - i) % n) < 2 or _shared(ni, nj, nlim) < 2:
                continue
            u = V[polygon[j]] - V[polygon[i]]
            L = float(np.linalg.norm(u))
            if L <= 0:
                continue
            u /= L
            a, b = float(di @ u), float(-dj @ u)
            if a > lim and b > lim and (best is None or a + b > best[0]):
                best = (a + b, i, j, di, dj)
    if best is None:
        return None
    q, i, j, di, dj = best
    pts = hermite(V[polygon[i]], di, V[polygon[j]], -dj, spacing)
    return CreaseSplit(int(i), int(j), pts, float(q))


def crease_corner(V: NDArray[np.float64], polygon: tuple[int, ...], ends: CreaseEnds, spacing: float, *,
                  max_miss: float = 0.15, rays: int = 3, min_turn: float = 30.0,
                  max_normal_turn: float = 30.0) -> tuple[CreaseSplit, int, NDArray[np.float64]] | None:
    """``rays`` (3 or 2) crease ends whose rays meet near one point C (a corner of the part): the
    split from the first end through C to the second (C is a vertex of its chain), the position of
    the third end (-1 for two rays: the crease turns at C), and C.

    The rays p_k + t d_k (t > 0) must pass within ``max_miss`` times their length to C of C; two
    rays must turn by at least ``min_turn`` degrees (straight ones are crease_split's). Every two
    of the rays must border one common surface (a face normal of each within ``max_normal_turn``
    degrees), as the edges of one corner do.
    """
    from itertools import combinations

    cand = ends.at(polygon, V)
    if len(cand) < rays:
        return None
    pts = V[list(polygon)]
    pad = 0.1 * float(np.linalg.norm(np.ptp(pts, axis=0)))
    lo, hi = pts.min(axis=0) - pad, pts.max(axis=0) + pad  # the corner lies over the hole
    best = None
    for combo in combinations(range(len(cand)), rays):  # few crease ends per hole
        tri = [cand[c] for c in combo]
        if len({k for k, _, _ in tri}) < rays:
            continue
        if rays == 2 and abs(float(tri[0][1] @ tri[1][1])) > np.cos(np.radians(min_turn)):
            continue
        nlim = np.cos(np.radians(max_normal_turn))
        if any(_shared(p[2], q[2], nlim) != 1 for p, q in combinations(tri, 2)):
            continue
        P = np.array([V[polygon[k]] for k, _, _ in tri])
        D = np.array([d for _, d, _ in tri])
        # least-squares point nearest the lines: sum (I - d d^T) (C - p) = 0
        A = sum(np.eye(3) - np.outer(d, d) for d in D)
        rhs = sum((np.eye(3) - np.outer(d, d)) @ p for d, p in zip(D, P))
        try:
            C = np.linalg.solve(A, rhs)
        except np.linalg.LinAlgError:
            continue
        t = np.einsum("ij,ij->i", C - P, D)
        if np.any(t <= 0) or np.any(C < lo) or np.any(C > hi):
            continue
        miss = np.linalg.norm(P + t[:, None] * D - C, axis=1) / t
        if np.all(miss < max_miss) and (best is None or miss.max() < best[0]):
            best = (float(miss.max()), tri, C, t)
    if best is None:
        return None
    _, tri, C, t = best
    (i, di, _), (j, dj, _) = tri[:2]
    k = tri[2][0] if rays == 3 else -1
    a = hermite(V[polygon[i]], di, C, di, spacing)
    b = hermite(C, -dj, V[polygon[j]], -dj, spacing)
    pts = np.vstack([a, C[None], b])
    return CreaseSplit(int(i), int(j), pts, float(3 - 3 * best[0])), int(k), C

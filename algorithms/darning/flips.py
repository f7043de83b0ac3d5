"""The Delaunay edge-flip passes of :func:`algorithms.darning.refine.relax`, compiled with numba.

One pass, exactly as refine.relax documents it: every patch-interior edge (a, b) next to a face
the previous pass changed, with opposite vertices c and d, violates the Delaunay test when the
angles at c and d sum to more than pi (the standard flip test on a surface, frep.md §4); a
violating edge is a candidate unless it is locked, its new edge (c, d) already exists (in the
patch in either direction, or among the fixed faces) or a new face would fold over (its normal
opposes the quad's). Candidates are taken worst first; each face takes part in at most one flip
(every face picks its most violating candidate, an edge flips when both its faces picked it) and
two flips never create the same edge. Passes repeat until none flips.

The passes are sequential and a patch has tens to hundreds of faces, so the per-pass cost of a
vectorised numpy version is call overhead; one compiled loop does the same work in microseconds.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import types
from numba.typed import Dict


@numba.njit(cache=True)
def _has(sorted_keys: np.ndarray, k: int) -> bool:
    n = sorted_keys.shape[0]
    if n == 0:
        return False
    i = np.searchsorted(sorted_keys, k)
    if i >= n:
        i = n - 1
    return sorted_keys[i] == k


@numba.njit(cache=True)
def _angle_at(p: np.ndarray, apex: int, a: int, b: int) -> float:
    """Angle at ``apex`` in the triangle (apex, a, b), radians: atan2(|u x w|, u . w)."""
    u0, u1, u2 = p[a, 0] - p[apex, 0], p[a, 1] - p[apex, 1], p[a, 2] - p[apex, 2]
    w0, w1, w2 = p[b, 0] - p[apex, 0], p[b, 1] - p[apex, 1], p[b, 2] - p[apex, 2]
    c0 = u1 * w2 - u2 * w1
    c1 = u2 * w0 - u0 * w2
    c2 = u0 * w1 - u1 * w0
    return np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2), u0 * w0 + u1 * w1 + u2 * w2)


@numba.njit(cache=True)
def _cross_dot(p: np.ndarray, o: int, x: int, y: int, n: np.ndarray) -> float:
    """((p[x] - p[o]) x (p[y] - p[o])) . n"""
    u0, u1, u2 = p[x, 0] - p[o, 0], p[x, 1] - p[o, 1], p[x, 2] - p[o, 2]
    w0, w1, w2 = p[y, 0] - p[o, 0], p[y, 1] - p[o, 1], p[y, 2] - p[o, 2]
    return (u1 * w2 - u2 * w1) * n[0] + (u2 * w0 - u0 * w2) * n[1] + (u0 * w1 - u1 * w0) * n[2]


@numba.njit(cache=True)
def flip_passes(p: np.ndarray, f: np.ndarray, fixed_keys: np.ndarray, locked_keys: np.ndarray,
                max_passes: int, index: bool = True) -> int:
    """Run the flip passes on ``f`` (M, 3) in place; edge keys are min * V + max (V = len(p)),
    fixed_keys / locked_keys sorted. Returns the number of flips.

    ``index``: the half-edges are indexed once (a dict from a * V + b to its half-edge, and each
    half-edge's twin) and the index is kept up to date flip by flip, so a pass walks the half-edges
    instead of sorting them. A patch in which a directed edge repeats (not an oriented manifold:
    the dict holds one half-edge per key) sorts them every pass, as ``index=False`` always does;
    the passes are the same either way."""
    nv = p.shape[0]
    nf = f.shape[0]
    nh = 3 * nf
    total = 0
    if nf == 0:
        return total
    where = Dict.empty(key_type=types.int64, value_type=types.int64)  # directed edge key -> its half-edge
    twin = np.full(nh, -1, dtype=np.int64)  # index mode: the twin half-edge; sorting: the twin key
    if index:
        for h in range(nh):
            k = f[h // 3, h % 3] * nv + f[h // 3, (h % 3 + 1) % 3]
            if k in where:
                index = False  # a directed edge twice
                break
            where[k] = h
    if index:
        for h in range(nh):
            k = f[h // 3, (h % 3 + 1) % 3] * nv + f[h // 3, h % 3]
            if k in where:
                twin[h] = where[k]
    active = np.ones(nf, dtype=np.bool_)
    key = np.empty(nh, dtype=np.int64)
    order = np.arange(nh)
    skey = np.empty(0, dtype=np.int64)
    h1 = np.empty(nh, dtype=np.int64)
    h2 = np.empty(nh, dtype=np.int64)
    score = np.empty(nh, dtype=np.float64)
    cc = np.empty(nh, dtype=np.int64)
    dd = np.empty(nh, dtype=np.int64)
    n_old = np.empty(3, dtype=np.float64)
    chosen = np.empty(nf, dtype=np.int64)
    for _ in range(max_passes):
        if not index:
            for h in range(nh):
                a = f[h // 3, h % 3]
                b = f[h // 3, (h % 3 + 1) % 3]
                key[h] = a * nv + b
                twin[h] = b * nv + a
            order = np.argsort(key, kind="mergesort")
            skey = key[order]
        m = 0  # interior edges next to an active face, each once (a < b), in half-edge order
        for h in range(nh):
            if f[h // 3, h % 3] >= f[h // 3, (h % 3 + 1) % 3]:
                continue
            if index:
                g = twin[h]
                if g < 0:
                    continue
            else:
                pos = min(np.searchsorted(skey, twin[h]), nh - 1)
                if skey[pos] != twin[h]:
                    continue
                g = order[pos]
            if active[h // 3] or active[g // 3]:
                h1[m] = h
                h2[m] = g
                m += 1
        if m == 0:
            break
        nc = 0  # candidates: violating, allowed, not folding
        for i in range(m):
            f1, f2 = h1[i] // 3, h2[i] // 3
            a, b = f[f1, h1[i] % 3], f[f1, (h1[i] % 3 + 1) % 3]
            c = f[f1, (h1[i] % 3 + 2) % 3]
            d = f[f2, (h2[i] % 3 + 2) % 3]
            s = _angle_at(p, c, a, b) + _angle_at(p, d, a, b) - np.pi
            if not (s > 1e-9) or c == d or _has(locked_keys, min(a, b) * nv + max(a, b)):
                continue
            if index:
                exists = (c * nv + d) in where or (d * nv + c) in where
            else:
                exists = _has(skey, c * nv + d) or _has(skey, d * nv + c)
            if exists or _has(fixed_keys, min(c, d) * nv + max(c, d)) or _folds(p, a, b, c, d, n_old):
                continue
            h1[nc], h2[nc], score[nc], cc[nc], dd[nc] = h1[i], h2[i], s, c, d
            nc += 1
        if nc == 0:
            break
        # independent set: each face picks its most violating candidate edge (stable: ties by order)
        rank = np.argsort(-score[:nc], kind="mergesort")
        chosen[:] = -1
        for r in range(nc):
            i = rank[r]
            for face in (h1[i] // 3, h2[i] // 3):
                if chosen[face] < 0:
                    chosen[face] = i
        made = set()
        made.add(-1)
        active[:] = False
        for r in range(nc):
            i = rank[r]
            f1, f2 = h1[i] // 3, h2[i] // 3
            if chosen[f1] != i or chosen[f2] != i:
                continue
            c, d = cc[i], dd[i]
            ek = min(c, d) * nv + max(c, d)
            if ek in made:  # two flips must not create the same edge
                continue
            made.add(ek)
            if index:  # the six half-edges leave the index ...
                for fc in (f1, f2):
                    for k in range(3):
                        del where[f[fc, k] * nv + f[fc, (k + 1) % 3]]
            a, b = f[f1, h1[i] % 3], f[f1, (h1[i] % 3 + 1) % 3]
            f[f1, 0], f[f1, 1], f[f1, 2] = c, a, d
            f[f2, 0], f[f2, 1], f[f2, 2] = d, b, c
            if index:  # ... and come back with their new faces, twins both ways
                _reindex(f, f1, f2, nv, where, twin)
            active[f1] = True
            active[f2] = True
            total += 1
    return total


@numba.njit(cache=True)
def _reindex(f: np.ndarray, f1: int, f2: int, nv: int, where, twin: np.ndarray) -> None:
    """Put the half-edges of faces f1 and f2 (just flipped) back into the index, with their twins."""
    for fc in (f1, f2):
        for k in range(3):
            where[f[fc, k] * nv + f[fc, (k + 1) % 3]] = 3 * fc + k
    for fc in (f1, f2):
        for k in range(3):
            h = 3 * fc + k
            back = f[fc, (k + 1) % 3] * nv + f[fc, k]
            if back in where:
                g = where[back]
                twin[h] = g
                twin[g] = h
            else:
                twin[h] = -1


@numba.njit(cache=True)
def _folds(p: np.ndarray, a: int, b: int, c: int, d: int, n_old: np.ndarray) -> bool:
    """Whether flipping edge (a, b) of faces (a, b, c), (b, a, d) folds: the new faces (c, a, d)
    and (d, b, c) must face like the old pair, n_old = (b - a) x (c - a) + (a - b) x (d - b)."""
    u0, u1, u2 = p[b, 0] - p[a, 0], p[b, 1] - p[a, 1], p[b, 2] - p[a, 2]
    w0, w1, w2 = p[c, 0] - p[a, 0], p[c, 1] - p[a, 1], p[c, 2] - p[a, 2]
    x0, x1, x2 = p[a, 0] - p[b, 0], p[a, 1] - p[b, 1], p[a, 2] - p[b, 2]
    y0, y1, y2 = p[d, 0] - p[b, 0], p[d, 1] - p[b, 1], p[d, 2] - p[b, 2]
    n_old[0] = (u1 * w2 - u2 * w1) + (x1 * y2 - x2 * y1)
    n_old[1] = (u2 * w0 - u0 * w2) + (x2 * y0 - x0 * y2)
    n_old[2] = (u0 * w1 - u1 * w0) + (x0 * y1 - x1 * y0)
    return not (_cross_dot(p, c, a, d, n_old) > 0 and _cross_dot(p, d, b, c, n_old) > 0)


@numba.njit(cache=True)
def edge_keys_among(f: np.ndarray, edges: np.ndarray, nv: int, faces: bool) -> np.ndarray:
    """Sorted unique keys min * nv + max of ``edges`` whose two ends are both vertices of ``f``
    (M, 3): the only ones flip_passes can ever look up (its candidate edges join patch vertices).
    ``edges``: (K, 3) faces (their three edges) if ``faces``, else (K, 2) vertex pairs."""
    mine = np.zeros(nv, dtype=np.bool_)
    for i in range(f.shape[0]):
        for k in range(3):
            mine[f[i, k]] = True
    per = 3 if faces else 1
    keys = np.empty(per * edges.shape[0], dtype=np.int64)
    n = 0
    for i in range(edges.shape[0]):
        for k in range(per):
            a = edges[i, k]
            b = edges[i, (k + 1) % 3] if faces else edges[i, 1]
            if mine[a] and mine[b]:
                keys[n] = min(a, b) * nv + max(a, b)
                n += 1
    return np.unique(keys[:n])

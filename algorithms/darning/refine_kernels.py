"""Compiled loops of the angle refinement (:func:`algorithms.darning.refine.refine_angles`).

The refinement's rounds are sequential and each round's work is a loop over a few hundred vertices
whose every step reads the positions the previous step wrote (smart Laplacian smoothing moves one
vertex against its neighbours' current positions); in numpy each step is a dozen small array calls
(~200 us of call overhead around ~2 us of arithmetic). Here the same steps run in one numba loop.
The arithmetic is refine.py's, in the same order; tests/test_refine_kernels.py compares each
kernel with the numpy function it replaces (kept in the test as its reference, as is the numpy
angle at a corner).
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

_HALF_SQRT3 = float(np.sqrt(3) / 2)


@numba.njit(cache=True)
def _angles_into(t: np.ndarray, out: np.ndarray) -> None:
    """out (K, 3): corner angles (radians) of the triangles t (K, 3, 3), as the numpy _tri_angles of
    tests/test_refine_kernels.py: atan2(|u x w|, u . w) with u, w the edges from the corner."""
    for i in range(t.shape[0]):
        for k in range(3):
            k1 = (k + 1) % 3
            k2 = (k + 2) % 3
            u0, u1, u2 = t[i, k1, 0] - t[i, k, 0], t[i, k1, 1] - t[i, k, 1], t[i, k1, 2] - t[i, k, 2]
            w0, w1, w2 = t[i, k2, 0] - t[i, k, 0], t[i, k2, 1] - t[i, k, 1], t[i, k2, 2] - t[i, k, 2]
            c0 = u1 * w2 - u2 * w1
            c1 = u2 * w0 - u0 * w2
            c2 = u0 * w1 - u1 * w0
            out[i, k] = np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2), u0 * w0 + u1 * w1 + u2 * w2)


@numba.njit(cache=True)
def _smooth_rounds(p: np.ndarray, f: np.ndarray, cand: np.ndarray, order: np.ndarray, start: np.ndarray,
                   stop: np.ndarray, tries: int, gain: float) -> int:
    """the reference smoothing loop's rounds on the candidates ``cand`` (stars: faces order[start:stop] // 3);
    moves p in place, returns the number of moves kept."""
    kmax = 0
    for q in range(cand.shape[0]):
        kmax = max(kmax, stop[q] - start[q])
    t = np.empty((kmax, 3, 3))
    tt = np.empty((kmax, 3, 3))
    ang = np.empty((kmax, 3))
    star = np.empty((kmax, 3), dtype=np.int64)
    n2 = np.empty((kmax, 3))
    trial = np.empty((6, 3))
    steps = np.array([1.0, 0.5, 0.25])
    nrm = np.empty(3)
    dl = np.empty((2, 3))
    kept = 0
    for _ in range(tries):  # sequential: each vertex moves against its neighbours' current positions
        moved = 0
        for q in range(cand.shape[0]):
            c = cand[q]
            ns = stop[q] - start[q]
            nnb = 0
            m0 = m1 = m2 = 0.0  # the sum of the neighbours (each twice unless on the star's rim)
            nrm[0] = nrm[1] = nrm[2] = 0.0
            for r in range(ns):
                row = order[start[q] + r] // 3
                for k in range(3):
                    v = f[row, k]
                    star[r, k] = v
                    for d in range(3):
                        t[r, k, d] = p[v, d]
                    if v != c:
                        nnb += 1
                        m0 += p[v, 0]
                        m1 += p[v, 1]
                        m2 += p[v, 2]
                a0, a1, a2 = t[r, 1, 0] - t[r, 0, 0], t[r, 1, 1] - t[r, 0, 1], t[r, 1, 2] - t[r, 0, 2]
                b0, b1, b2 = t[r, 2, 0] - t[r, 0, 0], t[r, 2, 1] - t[r, 0, 1], t[r, 2, 2] - t[r, 0, 2]
                nrm[0] += a1 * b2 - a2 * b1
                nrm[1] += a2 * b0 - a0 * b2
                nrm[2] += a0 * b1 - a1 * b0
            nn = np.sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2])
            if nnb == 0 or nn == 0:
                continue
            nrm[0] /= nn
            nrm[1] /= nn
            nrm[2] /= nn
            _angles_into(t[:ns], ang[:ns])
            before = 1e300
            worst = 0
            worst_min = 1e300
            for r in range(ns):
                fm = min(ang[r, 0], ang[r, 1], ang[r, 2])
                before = min(before, fm)
                if fm < worst_min:
                    worst_min = fm
                    worst = r
            # the face with the smallest angle: the equilateral apex on its edge opposite c
            kc = 0
            while star[worst, kc] != c:
                kc += 1
            ia, ib = star[worst, (kc + 1) % 3], star[worst, (kc + 2) % 3]
            e0, e1, e2 = p[ib, 0] - p[ia, 0], p[ib, 1] - p[ia, 1], p[ib, 2] - p[ia, 2]
            s0 = nrm[1] * e2 - nrm[2] * e1
            s1 = nrm[2] * e0 - nrm[0] * e2
            s2 = nrm[0] * e1 - nrm[1] * e0
            sl = max(np.sqrt(s0 * s0 + s1 * s1 + s2 * s2), 1e-300)
            s0, s1, s2 = s0 / sl, s1 / sl, s2 / sl
            h0, h1, h2 = (p[ia, 0] + p[ib, 0]) / 2, (p[ia, 1] + p[ib, 1]) / 2, (p[ia, 2] + p[ib, 2]) / 2
            if s0 * (p[c, 0] - h0) + s1 * (p[c, 1] - h1) + s2 * (p[c, 2] - h2) < 0:
                s0, s1, s2 = -s0, -s1, -s2
            el = _HALF_SQRT3 * np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
            dl[0, 0], dl[0, 1], dl[0, 2] = m0 / nnb - p[c, 0], m1 / nnb - p[c, 1], m2 / nnb - p[c, 2]
            dl[1, 0], dl[1, 1], dl[1, 2] = h0 + el * s0 - p[c, 0], h1 + el * s1 - p[c, 1], h2 + el * s2 - p[c, 2]
            dn = np.dot(dl, nrm)  # BLAS, as numpy's dl @ nrm (the same rounding)
            for j in range(2):  # in the tangent plane
                for d in range(3):
                    dl[j, d] -= dn[j] * nrm[d]
            for j in range(2):
                for s in range(3):
                    for d in range(3):
                        trial[3 * j + s, d] = p[c, d] + steps[s] * dl[j, d]
            best_score = -2.0
            b = 0
            for s in range(6):
                for r in range(ns):
                    for k in range(3):
                        for d in range(3):
                            tt[r, k, d] = trial[s, d] if star[r, k] == c else t[r, k, d]
                    a0, a1, a2 = tt[r, 1, 0] - tt[r, 0, 0], tt[r, 1, 1] - tt[r, 0, 1], tt[r, 1, 2] - tt[r, 0, 2]
                    b0, b1, b2 = tt[r, 2, 0] - tt[r, 0, 0], tt[r, 2, 1] - tt[r, 0, 1], tt[r, 2, 2] - tt[r, 0, 2]
                    n2[r, 0] = a1 * b2 - a2 * b1
                    n2[r, 1] = a2 * b0 - a0 * b2
                    n2[r, 2] = a0 * b1 - a1 * b0
                fold = (np.dot(n2[:ns], nrm) <= 0).any()  # BLAS, as numpy's n2 @ nrm
                _angles_into(tt[:ns], ang[:ns])
                score = 1e300
                for r in range(ns):
                    score = min(score, ang[r, 0], ang[r, 1], ang[r, 2])
                if fold:
                    score = -1.0  # a fold
                if score > best_score:
                    best_score = score
                    b = s
            if best_score > before + gain:
                p[c, 0], p[c, 1], p[c, 2] = trial[b, 0], trial[b, 1], trial[b, 2]
                moved += 1
        kept += moved
        if not moved:
            break
    return kept


def smooth_bad(p: NDArray[np.float64], f: NDArray[np.int64], free: NDArray[np.bool_], bad: NDArray[np.int64], *,
               tries: int = 3, gain: float = float(np.radians(0.1))) -> int:
    """The numpy smoothing loop (its reference in tests/test_refine_kernels.py) compiled: the same
    candidates, stars, trial points and acceptance rule;
    moves the free vertices of the bad faces in place and returns the number of moves kept."""
    f = np.ascontiguousarray(f, dtype=np.int64)
    cand, order, start, stop = stars(f, free, bad)
    if not len(cand):
        return 0
    return int(_smooth_rounds(p, f, cand, order, start, stop, int(tries), float(gain)))


def stars(f: NDArray[np.int64], free: NDArray[np.bool_], bad: NDArray[np.int64]
          ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """The free vertices of the bad faces and their stars: (cand, order, start, stop), the faces
    around cand[i] being f[order[start[i]:stop[i]] // 3]."""
    cand = np.unique(f[bad])
    cand = cand[free[cand]]
    order = np.argsort(f.ravel(), kind="stable")
    flat = f.ravel()[order]
    return cand, order, np.searchsorted(flat, cand), np.searchsorted(flat, cand, side="right")


@numba.njit(cache=True)
def _unchangeable_kernel(f: np.ndarray, nv: int, fixed: np.ndarray, locked: np.ndarray) -> np.ndarray:
    m = f.shape[0]
    mine = np.zeros(nv, dtype=np.bool_)
    for i in range(m):
        for k in range(3):
            mine[f[i, k]] = True
    # the border / locked edges between two vertices of f: the only ones an edge of f can be
    keys = np.empty(3 * fixed.shape[0] + locked.shape[0], dtype=np.int64)
    nk = 0
    for i in range(fixed.shape[0]):
        for k in range(3):
            a, b = fixed[i, k], fixed[i, (k + 1) % 3]
            if mine[a] and mine[b]:
                keys[nk] = min(a, b) * nv + max(a, b)
                nk += 1
    for i in range(locked.shape[0]):
        a, b = locked[i, 0], locked[i, 1]
        if mine[a] and mine[b]:
            keys[nk] = min(a, b) * nv + max(a, b)
            nk += 1
    ks = np.sort(keys[:nk])
    fk = np.empty(3 * m, dtype=np.int64)
    for i in range(m):
        for k in range(3):
            a, b = f[i, k], f[i, (k + 1) % 3]
            fk[3 * i + k] = min(a, b) * nv + max(a, b)
    fs = np.sort(fk)
    out = np.empty((m, 3), dtype=np.bool_)
    for h in range(3 * m):
        key = fk[h]
        j = np.searchsorted(ks, key)
        hit = j < nk and ks[j] == key
        lo = np.searchsorted(fs, key)
        single = lo + 1 >= 3 * m or fs[lo + 1] != key  # fewer than two faces of f hold the edge
        out[h // 3, h % 3] = hit or single
    return out


def unchangeable(f: NDArray[np.int64], nv: int, fixed: NDArray[np.int64],
                 locked: NDArray[np.int64] | None) -> NDArray[np.bool_]:
    """(M, 3) whether edge k of each patch face (f[:, k] -> f[:, k+1]) can neither split nor flip: a
    hole border edge (an edge of a fixed face), a locked edge, or an edge with one patch face.
    Compiled; its numpy reference is in tests/test_refine_kernels.py."""
    f = np.ascontiguousarray(f, dtype=np.int64).reshape(-1, 3)
    fx = np.ascontiguousarray(fixed, dtype=np.int64).reshape(-1, 3)
    lk = np.zeros((0, 2), dtype=np.int64) if locked is None else np.ascontiguousarray(locked, dtype=np.int64)
    return _unchangeable_kernel(f, int(nv), fx, lk.reshape(-1, 2))


@numba.njit(cache=True)
def _corner_angles_kernel(p: np.ndarray, f: np.ndarray) -> np.ndarray:
    m = f.shape[0]
    out = np.empty((m, 3))
    for i in range(m):
        for k in range(3):
            x, a, b = f[i, k], f[i, (k + 1) % 3], f[i, (k + 2) % 3]
            u0, u1, u2 = p[a, 0] - p[x, 0], p[a, 1] - p[x, 1], p[a, 2] - p[x, 2]
            w0, w1, w2 = p[b, 0] - p[x, 0], p[b, 1] - p[x, 1], p[b, 2] - p[x, 2]
            c0 = u1 * w2 - u2 * w1
            c1 = u2 * w0 - u0 * w2
            c2 = u0 * w1 - u1 * w0
            # u . w summed as numpy's einsum does it for three terms here ((0 + 2) + 1, from +0: a zero
            # edge gives +0, angle 0, not -0, angle pi): the same bits
            out[i, k] = np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2), ((u0 * w0 + u2 * w2) + u1 * w1) + 0.0)
    return out


def corner_angles(p: NDArray[np.float64], f: NDArray[np.int64]) -> NDArray[np.float64]:
    """(M, 3) angle at each corner of each face, radians (column k: at f[:, k]): refine.corner_angles
    compiled (atan2(|u x w|, u . w) per corner, no (M, 3) temporaries)."""
    return _corner_angles_kernel(np.ascontiguousarray(p, dtype=np.float64),
                                 np.ascontiguousarray(f, dtype=np.int64).reshape(-1, 3))


@numba.njit(cache=True)
def _star_scores_kernel(t: np.ndarray, at: np.ndarray, x: np.ndarray, n_old: np.ndarray) -> np.ndarray:
    k_count = x.shape[0]
    s = t.shape[0]
    out = np.empty(k_count)
    tt = np.empty((s, 3, 3))
    ang = np.empty((s, 3))
    for k in range(k_count):
        for i in range(s):
            for j in range(3):
                for d in range(3):
                    tt[i, j, d] = x[k, d] if at[i, j] else t[i, j, d]
        fold = False
        for i in range(s):
            u0, u1, u2 = tt[i, 1, 0] - tt[i, 0, 0], tt[i, 1, 1] - tt[i, 0, 1], tt[i, 1, 2] - tt[i, 0, 2]
            w0, w1, w2 = tt[i, 2, 0] - tt[i, 0, 0], tt[i, 2, 1] - tt[i, 0, 1], tt[i, 2, 2] - tt[i, 0, 2]
            c0 = u1 * w2 - u2 * w1
            c1 = u2 * w0 - u0 * w2
            c2 = u0 * w1 - u1 * w0
            if c0 * n_old[i, 0] + c1 * n_old[i, 1] + c2 * n_old[i, 2] <= 0:
                fold = True
                break
        if fold:
            out[k] = -1.0
            continue
        _angles_into(tt, ang)
        m = np.inf
        for i in range(s):
            for j in range(3):
                if ang[i, j] < m:
                    m = ang[i, j]
        out[k] = m
    return out


def star_scores(t: NDArray[np.float64], at: NDArray[np.bool_], x: NDArray[np.float64],
                n_old: NDArray[np.float64]) -> NDArray[np.float64]:
    """(K,) the smallest angle (radians) of a star (S, 3, 3 corner positions) with the corners ``at``
    (S, 3) moved to each candidate x[k], or -1 where a face folds (its normal against ``n_old`` (S, 3),
    the star's normals before the move): refine._move_best's grid score, compiled (its numpy
    reference is in tests/test_refine_kernels.py)."""
    return _star_scores_kernel(np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(at),
                               np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3),
                               np.ascontiguousarray(n_old, dtype=np.float64))


@numba.njit(cache=True)
def _grid_search_kernel(t: np.ndarray, at: np.ndarray, centre: np.ndarray, half: float, e1: np.ndarray,
                        e2: np.ndarray, n_old: np.ndarray, threshold: float, grid: int, levels: int) -> np.ndarray:
    best_m = threshold
    best = np.full(3, np.nan)
    x = np.empty((grid * grid, 3))
    c = centre.copy()
    for _ in range(levels):
        for i in range(grid):
            for j in range(grid):
                a = (-1.0 + 2.0 * j / (grid - 1)) * half
                b = (-1.0 + 2.0 * i / (grid - 1)) * half
                for d in range(3):
                    x[i * grid + j, d] = c[d] + a * e1[d] + b * e2[d]
        score = _star_scores_kernel(t, at, x, n_old)
        k = int(np.argmax(score))
        if score[k] > best_m:
            best_m = score[k]
            best[:] = x[k]
        if np.isnan(best[0]):
            return best
        c[:] = best
        half = half * 2.0 / (grid - 1) * 2
    return best


def grid_search(t: NDArray[np.float64], at: NDArray[np.bool_], centre: NDArray[np.float64], half: float,
                e1: NDArray[np.float64], e2: NDArray[np.float64], n_old: NDArray[np.float64], threshold: float,
                grid: int, levels: int) -> NDArray[np.float64]:
    """refine._move_best's search, compiled: ``levels`` rounds of a ``grid`` x ``grid`` grid of points
    centre + a e1 + b e2 (|a|, |b| <= half), each round around the best point so far with the spacing of
    two grid steps as its new half width; returns the point whose :func:`star_scores` is largest and
    above ``threshold``, or NaNs (the same points, in the same order, as the numpy loop it replaced)."""
    return _grid_search_kernel(np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(at),
                               np.asarray(centre, dtype=np.float64), float(half), np.asarray(e1, dtype=np.float64),
                               np.asarray(e2, dtype=np.float64), np.ascontiguousarray(n_old, dtype=np.float64),
                               float(threshold), int(grid), int(levels))

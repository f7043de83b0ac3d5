"""The per-round tests of :func:`algorithms.darning.refine.refine`, compiled with numba.

A hole's patch has tens to hundreds of faces and refine runs a few rounds per fairing round, so
the vectorised numpy form of these tests cost call overhead, not arithmetic. Same formulas, same
operation order (the results are bitwise those of the numpy form):

- ``centroid_splits``: the split test of frep.md §4 at every face (centroid v_c, l(v_c) the mean
  of the corners' l, alpha |v_c - v_m| > l(v_c) and > l(v_m) at every corner m);
- ``obtuse_edges``: the patch-interior edges, with the larger of the two angles facing each and
  whether the edge is longer than half its ends' mean scale (refine's obtuse-edge splitting).
"""

from __future__ import annotations

import numba
import numpy as np

from .flips import _angle_at


@numba.njit(cache=True)
def centroid_splits(p: np.ndarray, f: np.ndarray, lv: np.ndarray,
                    density: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(split (M,) bool, v_c (M, 3), l(v_c) (M,)) for the faces f (M, 3) of points p with scale lv."""
    m = f.shape[0]
    split = np.zeros(m, dtype=np.bool_)
    vc = np.empty((m, 3))
    lc = np.empty(m)
    for i in range(m):
        a, b, c = f[i, 0], f[i, 1], f[i, 2]
        for j in range(3):
            vc[i, j] = (p[a, j] + p[b, j] + p[c, j]) / 3
        lc[i] = (lv[a] + lv[b] + lv[c]) / 3
        ok = True
        for k in range(3):
            q = f[i, k]
            d0, d1, d2 = vc[i, 0] - p[q, 0], vc[i, 1] - p[q, 1], vc[i, 2] - p[q, 2]
            dist = density * np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if not (dist > lc[i] and dist > lv[q]):
                ok = False
        split[i] = ok
    return split, vc, lc


@numba.njit(cache=True)
def obtuse_edges(p: np.ndarray, f: np.ndarray, lv: np.ndarray, limit: float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(h1, h2, worst) of the patch-interior edges (each once, from its half-edge a -> b with a < b,
    in half-edge order; h2 its twin) facing an angle above ``limit`` radians on either side and
    longer than half their ends' mean scale: worst = the larger facing angle."""
    nv = p.shape[0]
    nh = 3 * f.shape[0]
    key = np.empty(nh, dtype=np.int64)
    for h in range(nh):
        key[h] = f[h // 3, h % 3] * nv + f[h // 3, (h % 3 + 1) % 3]
    order = np.argsort(key)
    skey = key[order]
    h1 = np.empty(nh, dtype=np.int64)
    h2 = np.empty(nh, dtype=np.int64)
    worst = np.empty(nh)
    m = 0
    for h in range(nh):
        a, b = f[h // 3, h % 3], f[h // 3, (h % 3 + 1) % 3]
        if a >= b:
            continue
        pos = np.searchsorted(skey, b * nv + a)
        if pos >= nh:
            pos = nh - 1
        if skey[pos] != b * nv + a:
            continue
        g = order[pos]
        c = f[h // 3, (h % 3 + 2) % 3]
        d = f[g // 3, (g % 3 + 2) % 3]
        w = max(_angle_at(p, c, a, b), _angle_at(p, d, a, b))
        d0, d1, d2 = p[a, 0] - p[b, 0], p[a, 1] - p[b, 1], p[a, 2] - p[b, 2]
        if w > limit and np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) > 0.5 * (lv[a] + lv[b]) / 2:
            h1[m], h2[m], worst[m] = h, g, w
            m += 1
    return h1[:m], h2[:m], worst[:m]

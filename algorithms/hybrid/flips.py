"""A finishing pass after Stage III (choice, not in the paper): edge flips that raise the minimum angle.

Between smoothing passes, an interior edge (not a border segment) shared by triangles (r, p, q) and
(s, q, p) is flipped to (r, p, s), (s, q, r) when the quad is strictly convex in (u, v) (so the
parameter triangulation stays valid), the smaller of the two triangles' minimum 3D angles grows by
more than `gain` degrees, and (when a chordal tolerance is given) the new triangles' chordal error
stays within it or within the old one. The candidates are assessed together (numpy, one surface
call); the flips are then applied in order of gain, at most one per triangle per pass.
"""

from __future__ import annotations

import numpy as np

from .cdt import Triangulation
from .chordal import chordal_errors
from .smooth import _min_angles


def flip_pass(tri: Triangulation, *, max_deviation: float | None = None, gain: float = 0.5,
              max_edge: float | None = None) -> int:
    """One pass; returns the number of flips. max_edge: no flip makes an edge longer than this."""
    T, K = [], []
    for t, (al, nb) in enumerate(zip(tri.alive, tri.tn)):
        if not al:
            continue
        for k in range(3):
            n = nb[k]
            if n > t and tri.alive[n]:
                T.append(t)
                K.append(k)
    if not T:
        return 0
    t1 = np.array(T)
    k1 = np.array(K)
    tv = np.array(tri.tv)
    tn = np.array(tri.tn)
    r = tv[t1, k1]
    p = tv[t1, (k1 + 1) % 3]
    q = tv[t1, (k1 + 2) % 3]
    t2 = tn[t1, k1]
    s = tv[t2].sum(axis=1) - p - q  # the vertex of t2 that is neither p nor q
    key = np.minimum(p, q), np.maximum(p, q)
    seg = {k for k in tri.seg}
    free = np.array([(a, b) not in seg for a, b in zip(*(x.tolist() for x in key))], dtype=bool)
    uv = np.array(tri.uv)
    P3 = np.array(tri.p3)

    def orient(a, b, c):
        return (uv[b, 0] - uv[a, 0]) * (uv[c, 1] - uv[a, 1]) - (uv[b, 1] - uv[a, 1]) * (uv[c, 0] - uv[a, 0])

    d2 = ((uv[r] - uv[s]) ** 2).sum(axis=1)
    convex = (orient(r, p, s) > 1e-9 * d2) & (orient(s, q, r) > 1e-9 * d2)
    old = np.minimum(_min_angles(P3[np.stack([r, p, q], 1)]), _min_angles(P3[np.stack([s, q, p], 1)]))
    A, B = np.stack([r, p, s], 1), np.stack([s, q, r], 1)
    new = np.minimum(_min_angles(P3[A]), _min_angles(P3[B]))
    ok = free & convex & (new > old + gain)
    if max_edge is not None:  # the new diagonal (r, s)
        ok &= np.sqrt(((P3[r] - P3[s]) ** 2).sum(axis=1)) <= max_edge
    cand = np.flatnonzero(ok)
    if not len(cand):
        return 0
    if max_deviation is not None:
        e_new = np.maximum(chordal_errors(tri.surface, P3[A[cand]], uv[A[cand]]),
                           chordal_errors(tri.surface, P3[B[cand]], uv[B[cand]]))
        Ao, Bo = np.stack([r, p, q], 1)[cand], np.stack([s, q, p], 1)[cand]
        e_old = np.maximum(chordal_errors(tri.surface, P3[Ao], uv[Ao]), chordal_errors(tri.surface, P3[Bo], uv[Bo]))
        cand = cand[e_new <= np.maximum(max_deviation, e_old)]
    order = cand[np.argsort(-(new[cand] - old[cand]), kind="stable")]
    touched: set[int] = set()
    done = 0
    for i in order.tolist():
        a, b = int(t1[i]), int(t2[i])
        if a in touched or b in touched:
            continue
        # the two triangles are unchanged since the assessment (no flip touched them)
        tri.flip(a, int(k1[i]))
        touched.update((a, b))
        done += 1
    return done

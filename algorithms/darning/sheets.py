"""Which faces around a patch its fairing may read: the smooth sheets of the input the patch
continues, not the faces beyond a sharp input edge.

**(choice)**, beyond spec/frep.md §4 (whose fairing reads every fixed face within k - 1 rings of the
patch): where a hole's border runs along a sharp edge of the part (a hole on one face of the part,
its border on the edge to the next face), the faces of the next face are fixed faces of the system,
and U3 = 0 bends the patch to continue them across the edge. Measured: bench/sweep.py cut
mushroom:6:0, a hole on the cap's nearly flat underside along its sharp rim, sagged 0.75 % of the
diagonal below the truth (MeshLib 0.01 %); a hole in a subdivided cylinder's side along its top
rim bulged out 11 % of the radius towards the top's plane.

The faces are grouped into sheets: two faces sharing an edge are one sheet when the edge is no
sharper than the crease angle, or when either face is not ``judged`` (the patch's own faces, and
the patches and chains darned before it: an unfaired fill or a bridge chain meets its border at any
angle, and judging those edges cut a thin part's fill off its island, bunny-islands 0.54 -> 1.96 %
of the diagonal). A sheet whose stretches of the patch's border all run along a crease is left out
(:func:`along_crease`), and so is a sheet the patch reaches only across a sharp edge
(:func:`reached_sheets`); a vertex with faces both kept and left out reads positions only (fair.py's
``bare``). Where a sharp edge crosses the hole, the crease chains (creases.py) split the hole first,
and each side reaches its own sheet through its border edges.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..mesh import face_normals
from ..topology import boundary_loops, face_adjacency

ALONG = 30.0  # degrees: a stretch of border goes on along a crease (along_crease)
ON_CURVE = 0.02  # of its chord: the stretch lies on the crease's continuation (along_crease)


def reached_sheets(vertices: NDArray[np.float64], faces: NDArray[np.int64], judged: NDArray[np.bool_],
                   seed: NDArray[np.bool_], crease_angle: float) -> NDArray[np.bool_]:
    """(F,) the faces reached from the ``seed`` faces, face to face across shared edges; an edge
    between two ``judged`` faces is crossed only when the angle between their normals is at most
    ``crease_angle`` degrees. ``judged``, ``seed``: (F,) bools."""
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    seed = np.asarray(seed, dtype=bool)
    if not len(f) or crease_angle >= 180:
        return np.ones(len(f), dtype=bool)
    judged = np.asarray(judged, dtype=bool)
    n = face_normals(vertices, f)
    a, b = face_adjacency(f, manifold_only=False).T
    ok = ~(judged[a] & judged[b]) | (np.einsum("ij,ij->i", n[a], n[b]) >= np.cos(np.radians(crease_angle)))
    label = _components(len(f), a[ok], b[ok])
    return np.isin(label, np.unique(label[seed]))


def _components(n: int, a: NDArray[np.int64], b: NDArray[np.int64]) -> NDArray[np.int64]:
    """(n,) the connected component of each of n faces, pairs (a, b) joined."""
    g = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    return connected_components(g, directed=False)[1]


def along_crease(vertices: NDArray[np.float64], faces: NDArray[np.int64], judged: NDArray[np.bool_],
                 region: NDArray[np.bool_], crease_angle: float, along: float = ALONG) -> NDArray[np.bool_]:
    """(F,) the judged faces of the sheets whose part of the ``region``'s border runs along a sharp
    edge: a hole on a flat face along the sharp rim of the next face of the part, its border on the
    rim, has the rim's other face beside that stretch of its border, and the fill continues the flat
    face, not that one.

    The judged faces are grouped into sheets (across edges no sharper than ``crease_angle``); each
    border edge of the region (``region``: (F,) bool, the patch faces) takes the sheet of the judged
    face across it. A stretch of border edges of one sheet runs along a crease when at both of its
    ends a sharp edge between judged faces arrives from outside and the stretch goes on in its
    direction (within ``along`` degrees), and the stretch lies within ``ON_CURVE`` of its chord from
    the curve that continues the crease from one end to the other (creases.hermite): the crease
    continues along the border (a slab across a turned part's circular rim meets it at a shallow
    angle at both ends, but its stretch runs along the chord, off the arc). A sheet all of
    whose stretches do so, on a border that has another sheet's stretch too, is returned. A crease
    that crosses the hole arrives at an angle to the border (creases.py joins its two ends by a
    chain instead)."""
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    judged = np.asarray(judged, dtype=bool)
    out = np.zeros(len(f), dtype=bool)
    region = np.asarray(region, dtype=bool)
    if crease_angle >= 180 or not judged.any() or not region.any():
        return out
    V = np.asarray(vertices, dtype=np.float64)
    n = face_normals(V, f)
    pairs, edge = face_adjacency(f, manifold_only=False, with_edges=True)
    a, b = pairs.T
    both = judged[a] & judged[b]
    smooth = np.einsum("ij,ij->i", n[a], n[b]) >= np.cos(np.radians(crease_angle))
    sheet = _components(len(f), a[both & smooth], b[both & smooth])
    nv = int(f.max()) + 1
    sharp: dict[int, list[int]] = {}  # vertex -> the other ends of its sharp edges between judged faces
    for lo, hi in np.unique(edge[both & ~smooth], axis=0).tolist():
        sharp.setdefault(lo, []).append(hi)
        sharp.setdefault(hi, []).append(lo)
    # the judged face across each border half-edge (a -> b of a region face: b -> a of the face beyond),
    # looked up in the judged faces' half-edges sorted by key
    jf = np.flatnonzero(judged)
    he = np.stack([f[jf], np.roll(f[jf], -1, axis=1)], axis=2).reshape(-1, 2)
    keys = he[:, 0] * nv + he[:, 1]
    order = np.argsort(keys, kind="stable")
    keys, owner = keys[order], np.repeat(jf, 3)[order]

    def sheets_across(loop: NDArray[np.int64]) -> NDArray[np.int64]:
        q = np.roll(loop, -1) * nv + loop
        i = np.minimum(np.searchsorted(keys, q), max(len(keys) - 1, 0))
        hit = keys[i] == q if len(keys) else np.zeros(len(q), dtype=bool)
        return np.where(hit, sheet[owner[i]] if len(keys) else -1, -1)

    stretches: dict[int, list[bool]] = {}  # sheet -> for each of its stretches, whether it runs along a crease
    for loop in boundary_loops(f[region]):
        m = len(loop)
        lab = sheets_across(np.asarray(loop, dtype=np.int64))
        if (lab == lab[0]).all():  # one sheet (or none) all round
            if lab[0] >= 0:
                stretches.setdefault(int(lab[0]), []).append(False)
            continue
        starts = [j for j in range(m) if lab[j] >= 0 and lab[j] != lab[j - 1]]
        for j0 in starts:
            j1 = j0
            while lab[(j1 + 1) % m] == lab[j0] and (j1 + 1) % m != j0:
                j1 = (j1 + 1) % m
            t0, t1 = int(loop[j0]), int(loop[(j1 + 1) % m])
            first = V[loop[(j0 + 1) % m]] - V[t0]  # the stretch's first edge, leaving t0
            last = V[t1] - V[loop[j1]]  # its last edge, arriving at t1
            d0 = _continues(V, t0, sharp.get(t0, ()), first, along, arriving=True)
            d1 = _continues(V, t1, sharp.get(t1, ()), last, along, arriving=False)
            on = d0 is not None and d1 is not None and t0 != t1
            if on:  # and the stretch lies on the curve the crease goes on along (not across its arc)
                idx = [int(loop[(j0 + q) % m]) for q in range(1, (j1 - j0) % m + 1)]
                on = _near_curve(V, t0, d0, t1, d1, idx, ON_CURVE)
            stretches.setdefault(int(lab[j0]), []).append(on)
    if len(stretches) < 2:
        return out
    drop = [s for s, runs in stretches.items() if all(runs)]
    if len(drop) == len(stretches):
        return out
    return judged & np.isin(sheet, drop)


def _continues(V: NDArray[np.float64], t: int, others, d: NDArray[np.float64], along: float, *,
               arriving: bool) -> NDArray[np.float64] | None:
    """The direction of a sharp edge (u, t) that goes on along ``d`` at t, or None: u -> t then d
    (``arriving``: the crease arrives at the stretch's start), or d then t -> u (it leaves at the
    stretch's end)."""
    lim = np.cos(np.radians(along))
    dn = d / max(float(np.linalg.norm(d)), 1e-300)
    best = None
    for u in others:
        e = V[t] - V[u] if arriving else V[u] - V[t]
        ln = float(np.linalg.norm(e))
        if ln > 0 and float(e @ dn) / ln >= lim and (best is None or float(e @ dn) / ln > float(best @ dn)):
            best = e / ln
    return best


def _near_curve(V: NDArray[np.float64], t0: int, d0: NDArray[np.float64], t1: int, d1: NDArray[np.float64],
                idx: list[int], tol: float) -> bool:
    """Whether the vertices ``idx`` lie within ``tol`` of the chord |t1 - t0| from the cubic Hermite
    curve from t0 (tangent d0) to t1 (tangent d1), the way creases.py continues a crease."""
    from ..bridge_graph import segment_distance
    from ..creases import hermite

    L = float(np.linalg.norm(V[t1] - V[t0]))
    if L <= 0:
        return False
    curve = np.vstack([V[t0], hermite(V[t0], d0, V[t1], d1, L / 64), V[t1]])
    if not idx:
        return True
    q = V[np.asarray(idx)][:, None, :]  # each point against every segment of the curve
    return bool(segment_distance(curve[:-1], curve[1:], q, q).min(axis=1).max() <= tol * L)


def sheet_system(vertices: NDArray[np.float64], faces: NDArray[np.int64], judged: NDArray[np.bool_],
                 free: NDArray[np.int64], crease_angle: float, region: NDArray[np.bool_] | None = None,
                 context: NDArray[np.int64] | None = None,
                 context_judged: NDArray[np.bool_] | None = None) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
    """The faces of a fairing system its free vertices' sheets hold, and the vertices left bare.

    Seeds: the faces with a free vertex; ``region`` (F,) bool: the patch faces whose border
    :func:`along_crease` reads (the sheets running along a crease are left out first); ``context``:
    (K, 3) more faces around the system, read for the sheets, the sharp edges and the patches'
    borders but not returned (a system cut to the rings its free vertices read may hold neither the
    sharp edge arriving at the border nor all of a patch); ``context_judged`` (K,): which of them
    are judged (default all); the others are patch faces (part of the region).
    Returns ((F,) bool, the kept faces; the vertices of kept faces that also have a
    face left out and are not free: their neighbourhood is cut)."""
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    n_sys = len(f)
    judged = np.asarray(judged, dtype=bool)
    if context is not None and len(context):
        f = np.vstack([f, np.asarray(context, dtype=np.int64).reshape(-1, 3)])
        cj = np.ones(len(f) - n_sys, dtype=bool) if context_judged is None else np.asarray(context_judged, dtype=bool)
        judged = np.r_[judged, cj]
        region = None if region is None else np.r_[np.asarray(region, dtype=bool), ~cj]
    isfree = np.zeros(max(int(f.max(initial=-1)) + 1, int(np.max(free, initial=-1)) + 1), dtype=bool)
    isfree[np.asarray(free, dtype=np.int64)] = True
    out = along_crease(vertices, f, judged, region, crease_angle) if region is not None else np.zeros(len(f), bool)
    keep = ~out
    keep[keep] = reached_sheets(vertices, f[keep], judged[keep], isfree[f[keep]].any(axis=1), crease_angle)
    keep, f = keep[:n_sys], f[:n_sys]
    if keep.all():
        return keep, np.zeros(0, dtype=np.int64)
    cut = np.intersect1d(np.unique(f[keep]), np.unique(f[~keep]))
    return keep, cut[~isfree[cut]]

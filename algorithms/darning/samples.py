"""Free points as samples of the missing surface, for the APSS projection of a fill (apss.py).

In full mode the free points (spec/repair.md §2, §8: PRAF, the free-point field) are samples of the
surface that is missing: they shape the fill, not only the bridges. The APSS needs a unit normal at
each data point; a free point has none, so it takes the one PRAF uses (§8 **(choice)**: N_P from
the principal axes of the points near X, the smallest axis), estimated over its ``k`` nearest
neighbours among the free points and the input's surface points together, with its sign aligned
with the current surface (§8: "sign aligned with the current normal"): the normal of the nearest
face of the faired fill (the fill already lies near the missing surface, a fraction of an edge to
a few edges off).

A free point far from every hole (beyond ``reach`` times the data spacing from the fill's new
vertices) says nothing about a fill and is left out, as are points whose neighbourhood is degenerate
(fewer than 3 distinct neighbours, or no plane: the two smallest principal values equal).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..mesh import face_cross


def principal_normals(points: NDArray[np.float64], cloud: NDArray[np.float64], *, k: int = 10,
                      tree: cKDTree | None = None) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """(K, 3) unit normals at ``points``: the smallest principal axis of the covariance of each
    point's ``k`` nearest neighbours in ``cloud`` (the point itself included if it is in the cloud),
    unsigned; and (K,) whether the estimate is usable (a planar neighbourhood: the smallest
    principal value below half the middle one)."""
    x = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    c = np.asarray(cloud, dtype=np.float64).reshape(-1, 3)
    if not len(x) or len(c) < 3:
        return np.zeros((len(x), 3)), np.zeros(len(x), dtype=bool)
    t = cKDTree(c) if tree is None else tree
    kk = int(min(k, len(c)))
    _, idx = t.query(x, k=kk)
    nb = c[idx.reshape(len(x), kk)]
    q = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("kji,kjl->kil", q, q) / kk
    w, vec = np.linalg.eigh(cov)  # ascending eigenvalues
    n = vec[:, :, 0]
    ok = (w[:, 0] < 0.5 * w[:, 1]) & (w[:, 1] > 0)
    return n, ok


def free_samples(free: NDArray[np.float64], V: NDArray[np.float64], F: NDArray[np.int64], surface: NDArray[np.float64],
                 new: NDArray[np.int64], *, spacing: float, k: int = 10,
                 reach: float = 6.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The free points that sample the missing surface around a fill, with oriented unit normals.

    free: (P, 3) the model's free points. V, F: the repaired surface so far (input and fill, the
    fill faired). surface: (M, 3) the input's surface points (for the principal axes). new: the fill's
    vertex indices into V. spacing: the data's edge length l. Returns (points (Q, 3), normals (Q, 3)),
    Q <= P (module docstring).
    """
    P = np.asarray(free, dtype=np.float64).reshape(-1, 3)
    new = np.asarray(new, dtype=np.int64)
    if not len(P) or not len(new) or not len(F):
        return np.zeros((0, 3)), np.zeros((0, 3))
    d, _ = cKDTree(V[new]).query(P, k=1)
    P = P[d <= reach * spacing]
    if not len(P):
        return np.zeros((0, 3)), np.zeros((0, 3))
    n, ok = principal_normals(P, np.vstack([P, surface]), k=k)
    # the sign: the normal of the nearest face (by centroid) of the fill and its surroundings
    near = np.zeros(len(V), dtype=bool)
    near[new] = True
    faces = F[near[F].any(axis=1)]
    if not len(faces):  # no face at the given vertices (a star prism's cut: every new vertex with faces held)
        return np.zeros((0, 3)), np.zeros((0, 3))
    t = V[faces]
    fn = face_cross(V, faces)
    _, j = cKDTree(t.mean(axis=1)).query(P, k=1)
    s = np.einsum("ij,ij->i", n, fn[j])
    ok &= s != 0
    n = n * np.sign(s)[:, None]
    return P[ok], n[ok]


def snap_to_samples(V: NDArray[np.float64], F: NDArray[np.int64], movable: NDArray[np.int64],
                    free: NDArray[np.float64], *, spacing: float, reach: float = 4.0, agree: float = 0.5,
                    n_fixed: int = 0) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Interpolation of the free points by the fill: each free point within ``reach`` * ``spacing``
    of the fill pulls the nearest vertex of the surface onto itself when that vertex is a ``movable``
    one (a free point whose nearest vertex is an input vertex samples the intact surface: nothing to
    do); a vertex pulled by several free points goes to their mean. The caller fairs the rest of the
    fill again with these vertices held (fair.py), so the fill passes through the samples of the
    missing surface and stays the smoothest surface that does (the soft version: the thin-plate
    energy with interpolation constraints). ``n_fixed``: vertices below this index are never moved.

    Returns (V with the pulled vertices moved, the pulled vertex indices)."""
    P = np.asarray(free, dtype=np.float64).reshape(-1, 3)
    mv = np.asarray(movable, dtype=np.int64)
    out = np.array(V, dtype=np.float64, copy=True)
    if not len(P) or not len(mv):
        return out, np.zeros(0, dtype=np.int64)
    can = np.zeros(len(V), dtype=bool)
    can[mv] = True
    can[:n_fixed] = False
    # the nearest vertex among the movable ones and among all (an input vertex nearer than every
    # movable one: the free point lies on the intact surface)
    d_all, _ = cKDTree(V).query(P, k=1)
    cand = np.flatnonzero(can)
    d, j = cKDTree(V[cand]).query(P, k=1)
    use = (d <= reach * spacing) & (d <= d_all + 1e-12)
    # a free point within ``agree`` * spacing of the fill along the vertex normal agrees with it
    # (within the sampling noise: interpolating noisy samples would only make the fill rough)
    v = cand[j]
    near = np.zeros(len(V), dtype=bool)
    near[v[use]] = True
    fs = F[near[F].any(axis=1)]
    fn = face_cross(V, fs)
    vn = np.zeros((len(V), 3))
    for k in range(3):
        np.add.at(vn, fs[:, k], fn)
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    off = np.abs(np.einsum("ij,ij->i", P - V[v], vn[v]))
    use &= off > agree * spacing
    if not use.any():
        return out, np.zeros(0, dtype=np.int64)
    tgt = cand[j[use]]
    verts, inv = np.unique(tgt, return_inverse=True)
    s = np.zeros((len(verts), 3))
    np.add.at(s, inv, P[use])
    out[verts] = s / np.bincount(inv, minlength=len(verts))[:, None]
    return out, verts

"""(choice) Isotropic improvement of an F-rep mesh: valence-driven edge flips and tangential
relaxation, every vertex kept on F = 0.

Not in the paper (spec/frep.md stops at U2 fairing); it is what makes the mesh *uniform*
(edge-length coefficient of variation) without changing its vertex count or its topology:

- **valence flips** (Botsch & Kobbelt's isotropic remeshing): the edge ab shared by the faces abc
  and bad becomes cd when that brings the four valences closer to 6, the two new faces turn by
  less than ``max_turn`` from the old ones and neither is flatter than the worse of the old pair;
  flips are made in rounds of independent edges (no two share a vertex), so every round is one
  vectorised step;
- **tangential relaxation**: each vertex moves towards the area-weighted centroid of its one-ring
  triangles (a step of Lloyd's CVT relaxation), within its tangent plane (normal -grad F), and is
  then projected back onto F = 0 (:func:`algorithms.frep.metrics.project`).

Connectivity changes only by flips: the vertex set, the Euler characteristic, the genus and the
orientation are kept.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..mesh import face_areas, face_cross
from ..topology import edge_table
from .metrics import project
from .objects import FRepObject


def _edge_faces(faces: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64],
                                                  NDArray[np.int64]]:
    """Interior edges as (E, 2) vertex pairs (a, b) with their two faces (E, 2) and the local
    index of a in the first face, such that face[0] runs a -> b; and every edge (sorted pairs)."""
    et = edge_table(faces)
    he = et.halfedge_edge  # half-edge h = 3 f + k runs faces[f, k] -> faces[f, (k + 1) % 3]
    order = np.argsort(he, kind="stable")
    hs = he[order]
    same = np.flatnonzero(hs[1:] == hs[:-1])
    keep = et.counts[hs[same]] == 2
    h1, h2 = order[same[keep]], order[same[keep] + 1]
    f1, k1 = h1 // 3, h1 % 3
    f2 = h2 // 3
    a = faces[f1, k1]
    b = faces[f1, (k1 + 1) % 3]
    return np.stack([a, b], axis=1), np.stack([f1, f2], axis=1), k1, et.edges


def _unit_normals(p: NDArray[np.float64], tri: NDArray[np.int64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    n = face_cross(p, tri)
    area2 = np.linalg.norm(n, axis=1)
    return n / np.maximum(area2, 1e-300)[:, None], area2


def _min_angle_cos(p: NDArray[np.float64], tri: NDArray[np.int64]) -> NDArray[np.float64]:
    """cos of each triangle's smallest angle (larger = worse)."""
    out = np.full(len(tri), -1.0)
    for k in range(3):
        o = p[tri[:, k]]
        u = p[tri[:, (k + 1) % 3]] - o
        v = p[tri[:, (k + 2) % 3]] - o
        c = np.einsum("ij,ij->i", u, v) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-300)
        out = np.maximum(out, c)
    return out


def valence_flips(vertices: NDArray[np.float64], faces: NDArray[np.int64], *, max_turn_deg: float = 20.0,
                  max_rounds: int = 50, rng: np.random.Generator | None = None) -> tuple[NDArray[np.int64], int]:
    """Flip edges while that brings valences closer to 6 (see the module text); returns
    (new faces, number of flips). Boundary edges and edges whose flip would duplicate an edge
    are never flipped."""
    p = np.asarray(vertices, dtype=np.float64)
    F = np.array(faces, dtype=np.int64, copy=True)
    rng = rng or np.random.default_rng(0)
    cos_turn = np.cos(np.radians(max_turn_deg))
    n = len(p)
    total = 0
    for _ in range(max_rounds):
        ab, ff, k1, edges = _edge_faces(F)
        if not len(ab):
            break
        a, b = ab[:, 0], ab[:, 1]
        c = F[ff[:, 0], (k1 + 2) % 3]
        f2 = F[ff[:, 1]]
        d = f2.sum(axis=1) - a - b  # the vertex of the second face that is not a or b
        val = np.bincount(edges.ravel(), minlength=n).astype(np.int64)
        before = (val[a] - 6) ** 2 + (val[b] - 6) ** 2 + (val[c] - 6) ** 2 + (val[d] - 6) ** 2
        after = (val[a] - 7) ** 2 + (val[b] - 7) ** 2 + (val[c] - 5) ** 2 + (val[d] - 5) ** 2
        gain = before - after
        ok = (gain > 0) & (c != d)
        if not ok.any():
            break
        # the new edge cd must not exist already
        existing = edges[:, 0] * n + edges[:, 1]
        cd = np.sort(np.stack([c, d], axis=1), axis=1)
        ok &= ~np.isin(cd[:, 0] * n + cd[:, 1], existing)
        # geometry: the new faces (a, d, c) and (d, b, c) turn little from the old and are not worse
        new1 = np.stack([a, d, c], axis=1)
        new2 = np.stack([d, b, c], axis=1)
        old1, old2 = F[ff[:, 0]], f2
        n_old1, _ = _unit_normals(p, old1)
        n_old2, _ = _unit_normals(p, old2)
        n_new1, ar1 = _unit_normals(p, new1)
        n_new2, ar2 = _unit_normals(p, new2)
        mean_old = n_old1 + n_old2
        mean_old /= np.maximum(np.linalg.norm(mean_old, axis=1, keepdims=True), 1e-300)
        ok &= np.einsum("ij,ij->i", n_new1, mean_old) > cos_turn
        ok &= np.einsum("ij,ij->i", n_new2, mean_old) > cos_turn
        ok &= (ar1 > 0) & (ar2 > 0)
        worst_old = np.maximum(_min_angle_cos(p, old1), _min_angle_cos(p, old2))
        worst_new = np.maximum(_min_angle_cos(p, new1), _min_angle_cos(p, new2))
        ok &= worst_new <= worst_old + 0.05  # (cos 0.05 ~ a few degrees of slack at 30-60 deg)
        idx = np.flatnonzero(ok)
        if not len(idx):
            break
        # independent set: an edge wins when its priority is the largest at all four vertices
        prio = gain[idx] + rng.random(len(idx)) * 0.5
        quad = np.stack([a[idx], b[idx], c[idx], d[idx]], axis=1)
        best = np.full(n, -np.inf)
        np.maximum.at(best, quad.ravel(), np.repeat(prio, 4))
        win = (best[quad] == prio[:, None]).all(axis=1)
        sel = idx[win]
        if not len(sel):
            break
        F[ff[sel, 0]] = new1[sel]
        F[ff[sel, 1]] = new2[sel]
        total += len(sel)
    return F, total


def cvt_relax(obj: FRepObject, vertices: NDArray[np.float64], faces: NDArray[np.int64], *, rounds: int,
              step: float = 0.8) -> NDArray[np.float64]:
    """Move each vertex towards the area-weighted centroid of its one-ring triangles within the
    tangent plane of F, then onto F = 0; ``rounds`` Jacobi rounds."""
    p = np.array(vertices, dtype=np.float64, copy=True)
    F = np.asarray(faces, dtype=np.int64)
    used = np.unique(F)
    n = len(p)
    for _ in range(rounds):
        tri = p[F]
        area = face_areas(p, F)
        cen = tri.mean(axis=1) * area[:, None]
        w = np.bincount(F.ravel(), weights=np.repeat(area, 3), minlength=n)
        target = np.stack([np.bincount(F.ravel(), weights=np.repeat(cen[:, j], 3), minlength=n) for j in range(3)],
                          axis=1)
        q = p[used]
        u = target[used] / np.maximum(w[used], 1e-300)[:, None] - q
        g = obj.gradient(q)
        g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)
        u -= np.einsum("ij,ij->i", u, g)[:, None] * g
        p[used] = project(obj, q + step * u, steps=3)
    return p


def improve(obj: FRepObject, vertices: NDArray[np.float64], faces: NDArray[np.int64], *, rounds: int,
            passes: int = 3) -> tuple[NDArray[np.float64], NDArray[np.int64], int]:
    """``passes`` x (valence flips, then rounds/passes relaxation rounds); returns (vertices,
    faces, flips)."""
    p = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    flips = 0
    per = max(1, -(-rounds // passes))
    done = 0
    while done < rounds:
        F, k = valence_flips(p, F)
        flips += k
        r = min(per, rounds - done)
        p = cvt_relax(obj, p, F, rounds=r)
        done += r
    return p, F, flips

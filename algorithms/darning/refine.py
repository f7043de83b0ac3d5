"""Refinement of a hole patch: centroid splitting with the edge-length scale, Delaunay edge flips
(Liepa 2003; spec/frep.md §4 "Adding vertices").

Each vertex of the hole border gets l(v), the mean length of its edges outside the patch; a
vertex made by a split gets l(v_c) = (l(v_i) + l(v_j) + l(v_k)) / 3. A patch face (v_i, v_j, v_k)
is split at its centroid v_c into three when, for every corner m,

    alpha |v_c - v_m| > l(v_c)   and   alpha |v_c - v_m| > l(v_m)                  (frep.md §4)

(alpha = ``density``; the spec's test is alpha = 1, Liepa uses sqrt 2 for a density matching the
surroundings). After the splits the patch edges are relaxed: an edge (a, b) with opposite
vertices c and d is flipped to (c, d) when d lies inside the circumcircle of (a, b, c) in the
plane of the faces, i.e. when the angles at c and d sum to more than pi (the standard Delaunay
flip test on a surface). Splitting and relaxing repeat until no face splits and no edge flips.

Only patch faces and patch-interior edges change; the fixed faces are never touched. Both steps
are vectorised over all faces / edges of a round; the rounds themselves are sequential.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..topology import edge_table, halfedges
from .flips import flip_passes


@dataclass(frozen=True, eq=False)
class Refined:
    """vertices: (V + K, 3), the input vertices then K new ones; faces: (M, 3) the patch faces;
    label: (M,) the label of the input patch face each face came from (splits inherit it)."""

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    label: NDArray[np.int64]
    splits: int
    flips: int
    rounds: int


def edge_scale(vertices: NDArray[np.float64], fixed_faces: NDArray[np.int64], n_vertices: int) -> NDArray[np.float64]:
    """(V,) l(v): mean length of v's edges among the fixed faces (NaN where v has none)."""
    v = np.asarray(vertices, dtype=np.float64)
    e = edge_table(np.asarray(fixed_faces, dtype=np.int64)).edges if len(fixed_faces) else np.zeros((0, 2), np.int64)
    ln = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    s = np.bincount(e.ravel(), weights=np.repeat(ln, 2), minlength=n_vertices)
    c = np.bincount(e.ravel(), minlength=n_vertices)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(c > 0, s / np.maximum(c, 1), np.nan)


def _angle_at(p: NDArray[np.float64], apex: NDArray[np.int64], a: NDArray[np.int64],
              b: NDArray[np.int64]) -> NDArray[np.float64]:
    """Angle at ``apex`` in the triangles (apex, a, b), radians."""
    u = p[a] - p[apex]
    w = p[b] - p[apex]
    return np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))


def relax(vertices: NDArray[np.float64], patch: NDArray[np.int64], fixed_faces: NDArray[np.int64], *,
          max_passes: int = 200, locked: NDArray[np.int64] | None = None) -> tuple[NDArray[np.int64], int]:
    """Delaunay edge flips on the patch-interior edges until none flips.

    One pass flips an independent set of violating edges at once (each face takes part in at
    most one flip: every face picks its most violating edge, an edge flips when both its faces
    picked it, so the worst edge always flips). A flip is refused when the new edge already
    exists (it would be non-manifold) or when a new face would fold over (its normal opposes the
    quad's). ``locked`` (K, 2): edges that never flip (e.g. a continued crease). Returns (faces,
    number of flips).
    """
    p = np.asarray(vertices, dtype=np.float64)
    f = np.array(patch, dtype=np.int64, copy=True).reshape(-1, 3)
    fixed = np.asarray(fixed_faces, dtype=np.int64).reshape(-1, 3)
    nv = len(p)
    fixed_keys = (np.unique(np.sort(halfedges(fixed), axis=1) @ np.array([nv, 1])) if len(fixed)
                  else np.zeros(0, np.int64))
    locked_keys = (np.unique(np.sort(np.asarray(locked, dtype=np.int64), axis=1) @ np.array([nv, 1]))
                   if locked is not None and len(locked) else np.zeros(0, np.int64))
    # the passes (the independent sets, the refusals) run compiled: flips.flip_passes
    total = int(flip_passes(p, f, fixed_keys, locked_keys, int(max_passes)))
    return f, total


def refine(vertices: NDArray[np.float64], fixed_faces: NDArray[np.int64], patch: NDArray[np.int64], *,
           density: float = np.sqrt(2.0), scale: NDArray[np.float64] | None = None, max_rounds: int = 60,
           flip: bool = True, label: NDArray[np.int64] | None = None,
           obtuse: float | None = 150.0, budget: float = 6.0) -> Refined:
    """Refine the patch faces ``patch`` (indices into ``vertices``) next to ``fixed_faces``.

    density: alpha of the split test (1 = the spec's test literally; sqrt 2 = Liepa's).
    scale: optional (V,) l(v) to use instead of the mean fixed edge length (NaN = unknown).
    Patch vertices without a scale (no fixed edge) get the mean of the known ones.
    obtuse: **(choice)** when nothing splits or flips any more, a patch-interior edge facing an
        angle above this many degrees is split at its midpoint, and the rounds go on (a
        near-flat sliver, e.g. Liepa's zero-area ear over three almost collinear border vertices,
        passes the centroid test and no flip can remove it); None: the spec's rounds only.
    budget: **(choice)** splitting stops once the patch has more than ``budget`` times the faces
        an even triangulation at the scale l would need (patch area / (sqrt(3)/4 l^2), plus the
        initial faces): a folded or self-overlapping patch, whose flips are refused, could
        otherwise split without end.
    """
    if not density > 0:
        raise ValueError(f"density must be > 0, got {density}")
    v = np.asarray(vertices, dtype=np.float64)
    f = np.array(patch, dtype=np.int64, copy=True).reshape(-1, 3)
    lab = np.arange(len(f)) if label is None else np.array(label, dtype=np.int64, copy=True)
    lv = edge_scale(v, fixed_faces, len(v)) if scale is None else np.array(scale, dtype=np.float64, copy=True)
    used = np.unique(f)
    known = used[np.isfinite(lv[used])]
    fill = float(lv[known].mean()) if len(known) else float(np.mean(
        np.linalg.norm(v[f] - v[np.roll(f, 1, axis=1)], axis=2))) if len(f) else 1.0
    lv[used[~np.isfinite(lv[used])]] = fill
    pts = [v]
    nv = len(v)
    splits = flips = 0
    tri = v[f]
    area = 0.5 * float(np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())
    max_faces = budget * (len(f) + area / (np.sqrt(3) / 4 * fill * fill)) if fill > 0 else np.inf
    rounds = 0
    while rounds < max_rounds:  # sequential: split, relax, repeat (frep.md §4)
        rounds += 1
        P = np.vstack(pts) if len(pts) > 1 else pts[0]
        t = P[f]
        vc = t.mean(axis=1)
        lc = lv[f].mean(axis=1)  # l(v_c)
        dist = density * np.linalg.norm(vc[:, None, :] - t, axis=2)
        split = np.all(dist > lc[:, None], axis=1) & np.all(dist > lv[f], axis=1)
        if len(f) + 2 * int(split.sum()) > max_faces:
            split[:] = False
        ns = int(split.sum())
        if ns:
            new = nv + np.arange(ns)
            nv += ns
            pts.append(vc[split])
            lv = np.concatenate([lv, lc[split]])
            s = f[split]
            keep = f[~split]
            f = np.vstack([keep, np.stack([s[:, 0], s[:, 1], new], 1), np.stack([s[:, 1], s[:, 2], new], 1),
                           np.stack([s[:, 2], s[:, 0], new], 1)])
            lab = np.concatenate([lab[~split], np.tile(lab[split], 3)])
            splits += ns
        nflip = 0
        if flip:
            P = np.vstack(pts) if len(pts) > 1 else pts[0]
            f, nflip = relax(P, f, fixed_faces)
            flips += nflip
        if not ns and not nflip:
            if obtuse is None or len(f) > max_faces:
                break
            P = np.vstack(pts) if len(pts) > 1 else pts[0]
            f, lab, mids, lm = _split_obtuse(P, f, lab, lv, nv, np.radians(obtuse))
            if not len(mids):
                break
            pts.append(mids)
            lv = np.concatenate([lv, lm])
            nv += len(mids)
            splits += len(mids)
    P = np.vstack(pts) if len(pts) > 1 else pts[0]
    return Refined(P, f, lab, splits, flips, rounds)


def _split_obtuse(p: NDArray[np.float64], f: NDArray[np.int64], lab: NDArray[np.int64], lv: NDArray[np.float64],
                  nv: int, limit: float) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64],
                                                  NDArray[np.float64]]:
    """Split the patch-interior edges facing an angle above ``limit`` (radians) at their midpoints;
    each face takes part in at most one split. Returns (faces, labels, new points, their l)."""
    he = halfedges(f)
    key = he[:, 0] * len(p) + he[:, 1]
    order = np.argsort(key)
    skey = key[order]
    twin = he[:, 1] * len(p) + he[:, 0]
    pos = np.minimum(np.searchsorted(skey, twin), len(key) - 1)
    h1 = np.flatnonzero((skey[pos] == twin) & (he[:, 0] < he[:, 1]))
    h2 = order[pos[h1]]
    a, b = he[h1, 0], he[h1, 1]
    c = f[h1 // 3, (h1 % 3 + 2) % 3]
    d = f[h2 // 3, (h2 % 3 + 2) % 3]
    worst = np.maximum(_angle_at(p, c, a, b), _angle_at(p, d, a, b))
    # only edges longer than half their ends' scale: halving them cannot go on for ever (a folded
    # patch, whose flips are refused, would otherwise split its obtuse edges without end)
    long_ = np.linalg.norm(p[a] - p[b], axis=1) > 0.5 * (lv[a] + lv[b]) / 2
    cand = np.flatnonzero((worst > limit) & long_)
    empty = np.zeros((0, 3))
    if not len(cand):
        return f, lab, empty, np.zeros(0)
    cand = cand[np.argsort(-worst[cand], kind="stable")]
    f1, f2 = h1[cand] // 3, h2[cand] // 3
    taken = np.zeros(len(f), dtype=bool)
    keep = []
    for i in range(len(cand)):  # sequential: a greedy independent set, worst edge first (few edges)
        if not taken[f1[i]] and not taken[f2[i]]:
            taken[f1[i]] = taken[f2[i]] = True
            keep.append(i)
    sel = cand[keep]
    f1, f2 = h1[sel] // 3, h2[sel] // 3
    a, b, c, d = a[sel], b[sel], c[sel], d[sel]
    m = nv + np.arange(len(sel))
    out = f.copy()
    out[f1] = np.stack([a, m, c], 1)
    out[f2] = np.stack([b, m, d], 1)
    out = np.vstack([out, np.stack([m, b, c], 1), np.stack([m, a, d], 1)])
    lab = np.concatenate([lab, lab[f1], lab[f2]])
    return out, lab, (p[a] + p[b]) / 2, (lv[a] + lv[b]) / 2

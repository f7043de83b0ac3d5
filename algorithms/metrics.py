"""Mesh quality and accuracy metrics, vectorised.

Angles and min-angle histograms (the quality report of the hybrid mesher, spec/hybrid.md §4),
a topology summary, distances to a reference surface (relative to its bounding-box diagonal) and
normal deviations. Shapes: V vertices, F faces, N sample points.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from .mesh import face_areas
from .topology import boundary_loops, edge_table, euler_characteristic, islands, orientation_consistent, vertex_fans


def triangle_angles(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(F, 3) interior angles in degrees; column k is the angle at corner k."""
    t = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    out = np.empty(t.shape[:2])
    for k in range(3):
        a = t[:, (k + 1) % 3] - t[:, k]
        b = t[:, (k + 2) % 3] - t[:, k]
        # atan2(|a x b|, a.b) is accurate for tiny and near-straight angles
        out[:, k] = np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b)))
    return out


def min_angles(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(F,) smallest angle of each triangle, degrees."""
    if not len(faces):
        return np.zeros(0)
    return triangle_angles(vertices, faces).min(axis=1)


def forced_faces(vertices: NDArray[np.float64], patch: NDArray[np.int64], border_edges: NDArray[np.int64], *,
                 below: float = 20.0, creases: NDArray[np.int64] | None = None) -> NDArray[np.bool_]:
    """(P,) whether each patch face's smallest angle (below ``below`` degrees) is **forced** by the
    input: it lies at a corner between two input border edges (``border_edges`` (E, 2), the edges
    of the hole borders, i.e. of the input faces used once). Every fill of that hole has that
    corner's angle, or smaller ones, there (e.g. a hole border corner of 10 degrees), so no patch
    can avoid it. Every other angle below the bound is unforced.

    ``creases`` (K, 2): patch edges that lie along a crease of the true surface leaving a border
    vertex (``along_true_creases``). A corner between a border edge and such an edge is forced too:
    a fill close to the truth has its crease there, so the wedge between the border and the crease
    is the same in every such fill (the fandisk's or featuretype's crease entering a hole at a
    small angle to the border)."""
    f = np.asarray(patch, dtype=np.int64).reshape(-1, 3)
    if not len(f):
        return np.zeros(0, dtype=bool)
    e = np.asarray(border_edges, dtype=np.int64).reshape(-1, 2)
    c = np.asarray(creases, dtype=np.int64).reshape(-1, 2) if creases is not None else np.zeros((0, 2), np.int64)
    nv = int(max(f.max(), e.max() if len(e) else 0, c.max() if len(c) else 0)) + 1

    def keys(x: NDArray[np.int64]) -> NDArray[np.int64]:
        return np.unique(np.sort(x, axis=1) @ np.array([nv, 1])) if len(x) else np.zeros(0, np.int64)

    border, crease = keys(e), keys(c)
    ang = triangle_angles(vertices, f)
    k = np.argmin(ang, axis=1)
    r = np.arange(len(f))
    x, a, b = f[r, k], f[r, (k + 1) % 3], f[r, (k + 2) % 3]
    xa, xb = np.minimum(x, a) * nv + np.maximum(x, a), np.minimum(x, b) * nv + np.maximum(x, b)  # its two edges
    ba, bb = np.isin(xa, border), np.isin(xb, border)
    on = (ba & bb) | (ba & np.isin(xb, crease)) | (bb & np.isin(xa, crease))
    return on & (ang[r, k] < below)


def along_true_creases(vertices: NDArray[np.float64], edges: NDArray[np.int64], truth_vertices: NDArray[np.float64],
                       truth_faces: NDArray[np.int64], *, angle: float = 40.0, within: float = 10.0,
                       tol: float = 1e-9) -> NDArray[np.bool_]:
    """(E,) whether each edge (x, y) leaves a vertex x of the truth (within ``tol`` of the
    diagonal) along one of the truth's sharp edges at x (dihedral above ``angle`` degrees): the
    edge's direction within ``within`` degrees of that sharp edge's. Both ends are tried."""
    from scipy.spatial import cKDTree

    from .creases import sharp_edges

    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    out = np.zeros(len(e), dtype=bool)
    tv = np.asarray(truth_vertices, dtype=np.float64)
    sharp, _ = sharp_edges(tv, np.asarray(truth_faces, dtype=np.int64), angle)
    if not len(e) or not len(sharp):
        return out
    v = np.asarray(vertices, dtype=np.float64)
    diag = float(np.linalg.norm(tv.max(axis=0) - tv.min(axis=0)))
    d, at = cKDTree(tv).query(v)
    at = np.where(d <= tol * diag, at, -1)
    # the truth's sharp half-edges (both directions), grouped by their start vertex
    src = np.concatenate([sharp[:, 0], sharp[:, 1]])
    u = np.concatenate([tv[sharp[:, 1]] - tv[sharp[:, 0]], tv[sharp[:, 0]] - tv[sharp[:, 1]]])
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    order = np.argsort(src, kind="stable")
    src, u = src[order], u[order]
    # every (edge, direction) against every sharp half-edge leaving the truth vertex it starts at
    x = np.concatenate([e[:, 0], e[:, 1]])
    y = np.concatenate([e[:, 1], e[:, 0]])
    s = at[x]
    lo = np.searchsorted(src, s, side="left")
    n = np.where(s >= 0, np.searchsorted(src, s, side="right") - lo, 0)
    q = np.repeat(np.arange(len(x)), n)
    h = np.repeat(lo - np.cumsum(n) + n, n) + np.arange(int(n.sum()))
    w = v[y[q]] - v[x[q]]
    w /= np.maximum(np.linalg.norm(w, axis=1, keepdims=True), 1e-300)
    hit = np.einsum("ij,ij->i", w, u[h]) > np.cos(np.radians(within))
    out[np.unique(q[hit] % len(e))] = True
    return out


@dataclass(frozen=True)
class AngleStats:
    """Summary of per-triangle minimum angles (degrees)."""

    count: int
    min: float
    p01: float  # 1st percentile
    median: float
    mean: float
    below_20: float  # share of triangles whose min angle is below 20 degrees
    below_30: float

    def as_dict(self) -> dict:
        return asdict(self)


def angle_stats(min_angle: NDArray[np.float64]) -> AngleStats:
    a = np.asarray(min_angle, dtype=np.float64)
    if not len(a):
        return AngleStats(0, float("nan"), float("nan"), float("nan"), float("nan"), 0.0, 0.0)
    return AngleStats(int(len(a)), float(a.min()), float(np.percentile(a, 1)), float(np.median(a)),
                      float(a.mean()), float((a < 20).mean()), float((a < 30).mean()))


def angle_histogram(min_angle: NDArray[np.float64], *, bin_width: float = 2.5,
                    upper: float = 60.0) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Histogram of min angles over [0, upper] (a triangle's min angle is at most 60 degrees).

    Returns (edges (B+1,), counts (B,)).
    """
    edges = np.arange(0.0, upper + bin_width / 2, bin_width)
    counts, _ = np.histogram(np.clip(min_angle, 0, upper), bins=edges)
    return edges, counts.astype(np.int64)


@dataclass(frozen=True)
class TopologySummary:
    watertight: bool  # closed and consistently oriented (every edge: two faces, opposite windings)
    manifold_edges: bool  # no edge has more than two faces
    oriented: bool
    components: int
    boundary_loops: int
    euler: int
    genus: float  # of the whole surface, from chi = 2c - 2g - b
    manifold_vertices: bool = True  # every vertex has one fan of faces (no pinch)

    def as_dict(self) -> dict:
        return asdict(self)


def topology(faces: NDArray[np.int64]) -> TopologySummary:
    faces = np.asarray(faces, dtype=np.int64)
    et = edge_table(faces)
    comps, _ = islands(faces)
    loops = boundary_loops(faces) if len(faces) else []
    chi = euler_characteristic(faces)
    manifold = bool(np.all(et.counts <= 2))
    oriented = orientation_consistent(faces)
    closed = bool(len(faces)) and bool(np.all(et.counts == 2))
    return TopologySummary(closed and oriented, manifold, oriented, comps, len(loops), chi,
                           (2 * comps - chi - len(loops)) / 2, not len(vertex_fans(faces)))


def edge_lengths(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(E,) lengths of the unique edges."""
    e = edge_table(np.asarray(faces)).edges
    v = np.asarray(vertices)
    return np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)


def edge_length_cv(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> float:
    """Coefficient of variation (std / mean) of edge lengths: a uniformity measure."""
    ln = edge_lengths(vertices, faces)
    return float(ln.std() / ln.mean()) if len(ln) and ln.mean() > 0 else 0.0


def surface_area(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> float:
    return float(face_areas(vertices, faces).sum())


def sample_surface(vertices: NDArray[np.float64], faces: NDArray[np.int64], n: int, *,
                   seed: int = 0) -> NDArray[np.float64]:
    """(n, 3) points uniformly distributed by area over the triangles."""
    t = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    area = face_areas(vertices, faces)
    rng = np.random.default_rng(seed)
    idx = rng.choice(len(t), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    w = np.stack([1 - s, s * (1 - r2), s * r2], axis=1)
    return np.einsum("nk,nkj->nj", w, t[idx])


def point_to_surface(points: NDArray[np.float64], vertices: NDArray[np.float64],
                     faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(N,) exact distance from each point to the triangle mesh (trimesh's closest point)."""
    import trimesh

    m = trimesh.Trimesh(np.asarray(vertices), np.asarray(faces), process=False)
    _, d, _ = trimesh.proximity.closest_point(m, np.asarray(points))
    return np.asarray(d)


@dataclass(frozen=True)
class Distances:
    """Sampled symmetric distances between a mesh and a reference, relative to the reference's
    bounding-box diagonal."""

    hausdorff: float
    mean: float
    to_reference_max: float  # mesh -> reference
    from_reference_max: float  # reference -> mesh
    diagonal: float  # the reference diagonal, in model units

    def as_dict(self) -> dict:
        return asdict(self)


def distance_samples(vertices: NDArray[np.float64], faces: NDArray[np.int64], ref_vertices: NDArray[np.float64],
                     ref_faces: NDArray[np.int64], *, samples: int = 20000, seed: int = 1
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The points ``distances`` measures and their exact distances: (points on the mesh, their
    distance to the reference, points on the reference, their distance to the mesh); each set is
    ``samples`` area-uniform points and the vertices."""
    rv = np.asarray(ref_vertices, dtype=np.float64)
    pm = np.vstack([sample_surface(vertices, faces, samples, seed=seed), np.asarray(vertices)])
    pr = np.vstack([sample_surface(rv, ref_faces, samples, seed=seed + 1), rv])
    return pm, point_to_surface(pm, rv, ref_faces), pr, point_to_surface(pr, vertices, faces)


def distances(vertices: NDArray[np.float64], faces: NDArray[np.int64], ref_vertices: NDArray[np.float64],
              ref_faces: NDArray[np.int64], *, samples: int = 20000, seed: int = 1) -> Distances:
    """Sampled symmetric Hausdorff and mean distance, exact point-to-surface both ways."""
    rv = np.asarray(ref_vertices, dtype=np.float64)
    diag = float(np.linalg.norm(rv.max(axis=0) - rv.min(axis=0)))
    _, d1, _, d2 = distance_samples(vertices, faces, rv, ref_faces, samples=samples, seed=seed)
    return Distances(float(max(d1.max(), d2.max()) / diag), float((d1.mean() + d2.mean()) / 2 / diag),
                     float(d1.max() / diag), float(d2.max() / diag), diag)


def normal_deviation(normals: NDArray[np.float64], reference: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N,) angle in degrees between each normal and its reference normal (orientation matters)."""
    a = np.asarray(normals, dtype=np.float64)
    b = np.asarray(reference, dtype=np.float64)
    a = a / np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-300)
    b = b / np.maximum(np.linalg.norm(b, axis=1, keepdims=True), 1e-300)
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b)))

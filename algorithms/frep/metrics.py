"""The paper's error metrics for a mesh of a functionally defined object (spec/frep.md §5).

* vertex deviation from the true surface: |F(v)| / |grad F(v)| (a first-order distance) and the
  projected distance (Newton steps along the gradient to F = 0);
* normal deviation from the true normal -grad F / |grad F| (F >= 0 inside, so the gradient
  points inwards), at the vertices (area-weighted vertex normals) and at the face centroids;
* uniformity: the coefficient of variation of edge lengths and the min-angle distribution.

Built on :mod:`algorithms.metrics` (angles, histograms, topology, edge lengths, normal deviation).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from .. import metrics as M
from ..boundary import vertex_normals
from ..mesh import Mesh, face_cross
from .objects import FRepObject


def first_order_distance(obj: FRepObject, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """|F(p)| / |grad F(p)|."""
    g = np.linalg.norm(obj.gradient(points), axis=1)
    return np.abs(obj.value(points)) / np.maximum(g, 1e-300)


def project(obj: FRepObject, points: NDArray[np.float64], *, steps: int = 8) -> NDArray[np.float64]:
    """Foot points on F = 0 by Newton steps along the gradient: p <- p - F grad F / |grad F|^2."""
    p = np.array(points, dtype=np.float64, copy=True)
    for _ in range(steps):  # Newton iterations (sequential by nature), vectorised over points
        g = obj.gradient(p)
        f = obj.value(p)
        p -= (f / np.maximum(np.einsum("ij,ij->i", g, g), 1e-300))[:, None] * g
    return p


def projected_distance(obj: FRepObject, points: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.linalg.norm(project(obj, points) - np.asarray(points), axis=1)


@dataclass(frozen=True)
class FrepMetrics:
    vertices: int
    faces: int
    topology: M.TopologySummary
    voxel: float  # the sampling cell S_xy in model units (the deviation scale)
    deviation_mean: float  # first-order |F| / |grad F|, model units
    deviation_max: float
    projected_mean: float  # projected distance to F = 0
    projected_max: float
    vertex_normal_mean: float  # degrees, vertex normals vs -grad F
    vertex_normal_p95: float
    vertex_normal_max: float
    face_normal_mean: float  # degrees, face normals vs -grad F at the centroid
    face_normal_p95: float
    face_normal_max: float
    edge_cv: float
    edge_mean: float
    angles: M.AngleStats
    histogram_edges: tuple[float, ...]
    histogram_counts: tuple[int, ...]

    def as_dict(self) -> dict:
        d = asdict(self)
        d["topology"] = self.topology.as_dict()
        d["angles"] = self.angles.as_dict()
        d["histogram_edges"] = list(self.histogram_edges)
        d["histogram_counts"] = list(self.histogram_counts)
        return d


def measure(obj: FRepObject, mesh: Mesh, *, voxel: float = float("nan")) -> FrepMetrics:
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    used = np.unique(f)
    dev = first_order_distance(obj, v[used])
    proj = projected_distance(obj, v[used])
    vn = vertex_normals(mesh)[used]
    true_v = -obj.gradient(v[used])
    vdev = M.normal_deviation(vn, true_v)
    t = v[f]
    fn = face_cross(v, f)
    ok = np.linalg.norm(fn, axis=1) > 0
    fdev = M.normal_deviation(fn[ok], -obj.gradient(t.mean(axis=1)[ok]))
    mins = M.min_angles(v, f)
    edges, counts = M.angle_histogram(mins)
    ln = M.edge_lengths(v, f)

    def stat(a: NDArray, q: float | None = None) -> float:
        if not len(a):
            return float("nan")
        return float(np.percentile(a, q)) if q is not None else float(a.mean())

    return FrepMetrics(int(len(used)), int(len(f)), M.topology(f), float(voxel),
                       stat(dev), float(dev.max(initial=0)), stat(proj), float(proj.max(initial=0)),
                       stat(vdev), stat(vdev, 95), float(vdev.max(initial=0)),
                       stat(fdev), stat(fdev, 95), float(fdev.max(initial=0)),
                       M.edge_length_cv(v, f), float(ln.mean()) if len(ln) else 0.0, M.angle_stats(mins),
                       tuple(float(e) for e in edges), tuple(int(c) for c in counts))

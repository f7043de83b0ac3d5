"""The three stages together (spec/hybrid.md §2-4) and the result that records them."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..mesh import Mesh
from ..metrics import AngleStats, TopologySummary, angle_histogram, angle_stats, min_angles, topology, triangle_angles
from .border import CURVE, Border, build_border
from .cdt import Triangulation
from .coarsen import coarsen_pass
from .flips import flip_pass
from .model import HybridModel
from .refine import RefineParams, Refiner, RefineStats
from .seeding import principal_lattice, seed_points
from .smooth import smooth as smooth_pass

COARSEN_PASSES = 8  # at most; each followed by a flip and a smoothing pass
MEDIAN_GAIN = 0.2  # degrees: finishing passes beyond `smooth` go on while they raise the median this much


@dataclass(frozen=True)
class HybridParams:
    """All parameters of the mesher.

    cells: background grid cells along the longer direction (Stage I); delta: short-edge merge
    length as a fraction of the 3D cell diagonal (§2 step 3, default 40 %); corner_angle: trim
    corners sharper than this (degrees) are excepted from the angle bound and reported; the rest
    are the Stage III parameters (:class:`RefineParams`); smooth: finishing passes (up to three
    times as many while they still raise the median minimum angle), each a pass of edge flips
    (flips.py) then one of smart smoothing (smooth.py), towards the ODT point and the Laplacian point
    in turn (choice: both keep the angle and chordal bounds and raise the median);
    coarsen_angle: after them, passes of half-edge and midpoint collapses (coarsen.py) remove the
    vertices the Stage III criteria do not need, keeping every bound, each new triangle's smallest
    angle at least this (degrees, >= min_angle; above it keeps the median min angle near 50: 36
    measured on the interstage cone; 0 disables);
    seed: (choice, with max_deviation) where the parameter lines are straight lines of curvature
    (cones, cylinders: seeding.py), a lattice of points with one edge along the rulings, sized by
    max_deviation across them, is inserted before Stage III (the same bounds, a fifth to a third
    fewer triangles on the interstage cone);
    median_floor: collapses keep the median of the triangles' minimum angles above this (degrees:
    at most half the triangles below it), and a pass that leaves it below after smoothing is undone
    and ends the coarsening."""

    min_angle: float = 30.0
    max_edge: float | None = None
    chord_arc: float = 0.98
    max_triangles: int = 200_000
    cells: int = 40
    delta: float = 0.4
    cylinder: float = 1.5
    corner_angle: float = 60.0
    border_chord_arc: float = 0.99
    max_deviation: float | None = None
    border_deviation: float | None = None
    smooth: int = 4
    coarsen_angle: float = 36.0
    seed: bool = True
    median_floor: float = 48.5
    refine: bool = True

    def __post_init__(self) -> None:
        self.refine_params()  # validates the Stage III fields
        if self.cells < 2:
            raise ValueError(f"cells: need at least 2, got {self.cells}")
        if not 0 <= self.delta < 1:
            raise ValueError(f"delta: must be in [0, 1), got {self.delta}")
        if self.smooth < 0:
            raise ValueError(f"smooth: the number of smoothing passes must be >= 0, got {self.smooth}")
        if self.coarsen_angle and not self.min_angle <= self.coarsen_angle < 60:
            raise ValueError(f"coarsen_angle: must be 0 (off) or in [min_angle, 60), got {self.coarsen_angle}")
        if not 0 < self.corner_angle <= 180:
            raise ValueError(f"corner_angle: must be in (0, 180], got {self.corner_angle}")

    def refine_params(self) -> RefineParams:
        return RefineParams(self.min_angle, self.max_edge, self.chord_arc, self.max_triangles, self.cylinder,
                            self.border_chord_arc, self.max_deviation, self.border_deviation)


@dataclass(frozen=True)
class HybridResult:
    """Every stage of one run, for reports and the explorer.

    border: Stage I (polylines in (u, v)). initial_*: Stage II (the CDT, W >= 0 part) in (u, v) and
    3D. uv / points / faces: the refined mesh before welding (faces index both uv and points).
    mesh: the welded output (seams of periodic directions merged); weld: (V,) index of each
    unwelded vertex in mesh. min_angle_before/after: per-triangle min angles (3D, degrees).
    corner_triangles: indices (into faces) of triangles at trim corners sharper than corner_angle.
    """

    model: HybridModel
    params: HybridParams
    border: Border
    initial_uv: NDArray[np.float64]
    initial_points: NDArray[np.float64]
    initial_faces: NDArray[np.int64]
    uv: NDArray[np.float64]
    points: NDArray[np.float64]
    faces: NDArray[np.int64]
    mesh: Mesh
    weld: NDArray[np.int64]
    min_angle_before: NDArray[np.float64]
    min_angle_after: NDArray[np.float64]
    corner_triangles: NDArray[np.int64]
    corner_vertices: NDArray[np.int64]
    border_vertices: NDArray[np.int64]
    max_abs_F: float
    max_border_distance: float
    timings: dict[str, float] = field(default_factory=dict)
    refine_stats: RefineStats | None = None
    smoothed_moves: int = 0
    flips: int = 0
    collapses: int = 0
    seeded: int = 0

    @property
    def stats_before(self) -> AngleStats:
        return angle_stats(self.min_angle_before)

    @property
    def stats_after(self) -> AngleStats:
        return angle_stats(self.min_angle_after)

    @property
    def stats_excluding_corners(self) -> AngleStats:
        keep = np.ones(len(self.faces), dtype=bool)
        keep[self.corner_triangles] = False
        return angle_stats(self.min_angle_after[keep])

    @property
    def topology(self) -> TopologySummary:
        return topology(self.mesh.faces)

    def report(self) -> dict:
        edges, counts = angle_histogram(self.min_angle_after)
        edges0, counts0 = angle_histogram(self.min_angle_before)
        rs = self.refine_stats
        return {
            "model": self.model.name,
            "params": {k: getattr(self.params, k) for k in self.params.__dataclass_fields__},
            "timings": dict(self.timings),
            "counts": {
                "border_vertices": int(len(self.border.points)),
                "border_segments": int(len(self.border.segments)),
                "ambiguous_cells": self.border.ambiguous_cells,
                "merged_short_edges": self.border.merged,
                "triangles_initial": int(len(self.initial_faces)),
                "triangles_final": int(len(self.faces)),
                "vertices_final": int(len(self.mesh.vertices)),
                "final_border_vertices": int(len(self.border_vertices)),
                "inserted_circumcentres": rs.inserted if rs else 0,
                "border_splits": rs.segment_splits if rs else 0,
                "smoothing_moves": self.smoothed_moves,
                "finishing_flips": self.flips,
                "collapses": self.collapses,
                "seeded": self.seeded,
            },
            "angles_before": self.stats_before.as_dict(),
            "angles_after": self.stats_after.as_dict(),
            "angles_after_excluding_corners": self.stats_excluding_corners.as_dict(),
            "histogram": {"edges": edges.tolist(), "after": counts.tolist(), "before": counts0.tolist()},
            "trim_corner_exceptions": {"vertices": int(len(self.corner_vertices)),
                                       "triangles": int(len(self.corner_triangles)),
                                       "min_angles": self.min_angle_after[self.corner_triangles].tolist()},
            "border": {"max_abs_F": self.max_abs_F, "max_distance": self.max_border_distance,
                       "max_distance_relative": self.max_border_distance / self.model.surface.size,
                       "off_curve_vertices": rs.off_curve if rs else 0},
            "hit_max_triangles": bool(rs.hit_limit) if rs else False,
            "topology": self.topology.as_dict(),
        }


def _corner_vertices(points: NDArray, faces: NDArray, border: NDArray, limit: float) -> NDArray[np.int64]:
    """Border vertices whose interior angle in the mesh (sum of 3D triangle angles) is below limit."""
    if not len(faces):
        return np.zeros(0, dtype=np.int64)
    ang = triangle_angles(points, faces)
    total = np.bincount(faces.ravel(), weights=ang.ravel(), minlength=len(points))
    sel = border[total[border] < limit]
    return sel.astype(np.int64)


def weld_seams(model: HybridModel, uv: NDArray, points: NDArray, faces: NDArray
               ) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """Merge the vertices of the two sides of each periodic direction (same point in space)."""
    s = model.surface
    a, b, c, d = s.domain
    n = len(points)
    rep = np.arange(n)
    on = np.zeros(n, dtype=bool)
    if s.periodic_u:
        on |= (uv[:, 0] <= a) | (uv[:, 0] >= b)
    if s.periodic_v:
        on |= (uv[:, 1] <= c) | (uv[:, 1] >= d)
    idx = np.flatnonzero(on)
    if len(idx):
        tol = 1e-9 * s.size
        tree = cKDTree(points[idx])
        for i, j in sorted(tree.query_pairs(tol)):  # union-find (few pairs)
            ri, rj = idx[i], idx[j]
            while rep[ri] != ri:
                ri = rep[ri]
            while rep[rj] != rj:
                rj = rep[rj]
            if ri != rj:
                rep[max(ri, rj)] = min(ri, rj)
        for k in range(n):
            r = k
            while rep[r] != r:
                r = rep[r]
            rep[k] = r
    used, inv = np.unique(rep, return_inverse=True)
    return points[used], inv[faces], inv


def mesh_hybrid(model: HybridModel, params: HybridParams | None = None) -> HybridResult:
    """Triangulate a hybrid parametric + implicit surface (Stages I-III)."""
    p = params or HybridParams()
    times: dict[str, float] = {}
    t0 = time.perf_counter()
    border = build_border(model, cells=p.cells, delta=p.delta)  # Stage I
    times["stage1_border"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    tri = Triangulation(model)
    tri.build(border)  # Stage II
    times["stage2_cdt"] = time.perf_counter() - t0
    uv0, p30, f0 = tri.arrays()
    before = min_angles(p30, f0)

    bverts = tri.border_vertices()
    f_all = tri.faces()
    P3_all = np.array(tri.p3)
    corners = _corner_vertices(np.nan_to_num(P3_all), f_all, bverts, p.corner_angle)

    t0 = time.perf_counter()
    stats = None
    seeded = 0
    if p.refine:
        ref = Refiner(tri, p.refine_params(), corners=set(corners.tolist()))
        if p.seed and p.max_deviation is not None:  # (choice) lines-of-curvature seeding, seeding.py
            lattice, h = principal_lattice(model, p.max_deviation, max_edge=p.max_edge)
            if len(lattice):
                ref.split_long_segments(1.5 * h)  # short border edges first: the seeds may come close to them
                segs = np.array([[tri.uv[a], tri.uv[b]] for _k, a, b in tri.seg.values()], dtype=np.float64)
                seeded = ref.seed(seed_points(model, lattice, h, segs.reshape(-1, 2, 2)))
        stats = ref.run()  # Stage III
    times["stage3_refine"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    moved = flipped = collapsed = 0
    passes = 0

    def finish(only: NDArray[np.bool_] | None = None) -> None:
        """One flip pass, one smoothing pass (ODT and Laplacian targets in turn); only: the vertices
        that may move."""
        nonlocal moved, flipped, passes
        flipped += flip_pass(tri, max_deviation=p.max_deviation, max_edge=p.max_edge)
        moved += smooth_pass(tri, passes=1, max_deviation=p.max_deviation, guard=p.min_angle + 0.25,
                             max_edge=p.max_edge, target="odt" if passes % 2 == 0 else "laplace", only=only)
        passes += 1

    def median() -> float:
        return float(np.median(min_angles(np.array(tri.p3), tri.faces())))

    if p.refine and p.smooth:  # finishing passes: flips that raise the min angle, then smoothing, in turn
        for _ in range(p.smooth):
            finish()
        m = median()
        for _ in range(2 * p.smooth):  # more while they still raise the median (coarse meshes, mostly)
            finish()
            m, m0 = median(), m
            if m < m0 + MEDIAN_GAIN:
                break
    times["smooth"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    if p.refine and p.coarsen_angle:
        active = None
        for _ in range(COARSEN_PASSES):  # until a pass removes under 1 % of the triangles
            undo = tri.snapshot(), moved, flipped
            c, changed = coarsen_pass(tri, min_angle=p.coarsen_angle, max_deviation=p.max_deviation,
                                      max_edge=p.max_edge, chord_arc=p.chord_arc, only=active,
                                      median_floor=p.median_floor)
            # the next pass looks only where triangles changed: this one's collapses and the smoothing
            # around them (one ring further)
            f = tri.faces()
            active = changed.copy()
            active[f[changed[f].any(axis=1)].ravel()] = True
            finish(only=active)
            if median() < p.median_floor:
                tri.restore(undo[0])  # this pass cost too much of the median
                moved, flipped = undo[1:]
                break
            collapsed += c
            if c < 0.02 * tri.n_alive:
                break
    if p.refine and (p.smooth or p.coarsen_angle):
        flipped += flip_pass(tri, max_deviation=p.max_deviation, max_edge=p.max_edge)
    times["coarsen"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    f = tri.faces()
    used = np.unique(f.ravel())
    remap = -np.ones(len(tri.uv), dtype=np.int64)
    remap[used] = np.arange(len(used))
    uv = np.array(tri.uv, dtype=np.float64)[used]
    pts = np.array(tri.p3, dtype=np.float64)[used]
    faces = remap[f]
    bv = remap[tri.border_vertices()]
    bv = bv[bv >= 0]
    cv = remap[corners]
    cv = cv[cv >= 0]
    after = min_angles(pts, faces)
    corner_tris = np.flatnonzero(np.isin(faces, cv).any(axis=1) & (after < p.min_angle))
    # border accuracy: |F| on the curve vertices, and the distance |F| / |grad F| (central differences)
    curve_v = np.unique(np.array([[s[1], s[2]] for s in tri.seg.values() if s[0] == CURVE],
                                 dtype=np.int64).reshape(-1, 2).ravel())
    curve_v = remap[curve_v]
    curve_v = curve_v[curve_v >= 0]
    max_f, max_d = 0.0, 0.0
    if len(curve_v) and model.trim is not None:
        q = pts[curve_v]
        fv = np.abs(model.F(q))
        h = 1e-6 * model.surface.size
        grad = np.stack([(model.F(q + h * e) - model.F(q - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
        gn = np.maximum(np.linalg.norm(grad, axis=1), 1e-300)
        max_f, max_d = float(fv.max()), float((fv / gn).max())
    wpts, wfaces, weld = weld_seams(model, uv, pts, faces)
    mesh = Mesh(wpts, wfaces)
    times["output"] = time.perf_counter() - t0
    times["total"] = sum(times.values())
    return HybridResult(model, p, border, uv0, p30, f0, uv, pts, faces, mesh, weld, before, after,
                        corner_tris, cv, bv, max_f, max_d, times, stats, moved, flipped, collapsed, seeded)

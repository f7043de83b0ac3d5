"""The whole F-rep triangulation (spec/frep.md §2-§5), recording every stage for replay.

sampling (quadtree + rays) -> linking (quads ABCD -> ABC, ACD) -> holes (loops of one-face
edges) -> filling (Liepa's minimum-weight triangulation) -> merging the patches with the
neighbouring faces of zero projected area (the sides parallel to the rays) -> refinement
(centroid splits + edge flips) -> fairing (U2 = 0) -> (choice) isotropic improvement (valence
flips + tangential CVT relaxation on F = 0, ``smooth`` rounds; remesh.py) -> metrics.

Filling, refinement and fairing are the shared darning code (:mod:`algorithms.darning`), the
same implementation the repair pipeline uses.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..mesh import Mesh, face_cross
from ..topology import boundary_loops, edge_table, face_adjacency
from .linking import DIAGONALS, Linked, link
from .metrics import FrepMetrics, first_order_distance, measure, project
from .objects import FRepObject
from .remesh import improve
from .sampling import Samples, SamplingParams, sample

WEIGHTS = ("area", "length")
FAIRINGS = ("U2", "U1", "none")


@dataclass(frozen=True)
class FrepParams:
    qlev: int = 6  # quadtree depth, S_xy = 1 / 2^qlev of the domain
    blev: int = 12  # ray subdivision depth, S_z = 1 / 2^blev
    diagonal: str = "shorter"  # (choice) quads split along the shorter diagonal, or "AC": ABC, ACD (the paper)
    weight: str = "area"  # Liepa weight: "area" or "length" (minimum total edge length)
    merge_sides: bool = True  # merge patches with neighbouring zero-projected-area faces before refining
    # faces with |n_z| <= side_slope (unit normal) are merged: ~0 is the paper's "zero projected
    # area"; (choice) the default 0.6 also takes the steep, stretched faces next to them
    side_slope: float = 0.6
    refine: bool = True  # centroid splitting + edge flips
    density: float = float(np.sqrt(2.0))  # alpha of the split test (1 = the spec literally, sqrt 2 = Liepa)
    fairing: str = "U2"  # U2 = 0 (bi-Laplacian), U1 = 0 (umbrella) or "none"
    project: bool = True  # (choice) finally move the new vertices onto F = 0 along the gradient
    # (choice) rounds of isotropic improvement of all vertices (remesh.py: valence flips + tangential
    # CVT relaxation, each projected onto F = 0); 0 = the paper's pipeline exactly
    smooth: int = 10

    def __post_init__(self) -> None:
        SamplingParams(self.qlev, self.blev)  # validates qlev and blev
        if self.diagonal not in DIAGONALS:
            raise ValueError(f"diagonal must be one of {DIAGONALS}, got {self.diagonal!r}")
        if self.weight not in WEIGHTS:
            raise ValueError(f"weight must be one of {WEIGHTS}, got {self.weight!r}")
        if self.fairing not in FAIRINGS:
            raise ValueError(f"fairing must be one of {FAIRINGS}, got {self.fairing!r}")
        if not 0 <= self.side_slope < 1:
            raise ValueError(f"side_slope must be in [0, 1), got {self.side_slope}")
        if not (isinstance(self.smooth, (int, np.integer)) and 0 <= self.smooth <= 100):
            raise ValueError(f"smooth must be an integer in 0..100, got {self.smooth!r}")
        if not self.density > 0:
            raise ValueError(f"density must be > 0, got {self.density}")


@dataclass(frozen=True, eq=False)
class Stage:
    """One step of the pipeline for replay: vertices, faces (none for the points), an optional
    (F,) face highlight and the hole loops (vertex ids)."""

    name: str
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    highlight: NDArray[np.bool_] | None = None
    loops: tuple[NDArray[np.int64], ...] = ()


@dataclass(frozen=True, eq=False)
class FrepResult:
    """Every stage of one run.

    samples: the surface points (and quadtree blocks, runs); linked: quads and successors;
    quad_mesh: the mesh after linking (with holes); loops: the hole loops (vertex ids of
    quad_mesh, positive direction); filled: after Liepa filling, filled_patch: (F,) bool, the
    patch faces; region: (F,) bool, the faces handed to refinement (patches + merged side
    faces); refined: after refinement; faired: after fairing (and projection): the result;
    metrics of the result; timings in seconds per stage.
    """

    obj: FRepObject
    params: FrepParams
    samples: Samples
    linked: Linked
    quad_mesh: Mesh
    loops: list[NDArray[np.int64]]
    filled: Mesh
    filled_patch: NDArray[np.bool_]
    region: NDArray[np.bool_]
    refined: Mesh
    refined_new: NDArray[np.bool_]  # (V,) vertices made by refinement
    faired: Mesh
    metrics: FrepMetrics
    timings: dict[str, float] = field(default_factory=dict)
    splits: int = 0
    flips: int = 0
    improve_flips: int = 0  # valence flips of the isotropic improvement (params.smooth rounds)

    @property
    def mesh(self) -> Mesh:
        return self.faired

    def stages(self) -> list[Stage]:
        """The stages in order, for the explorer's timeline: points, quads, holes (the quad mesh
        with the hole loops), filled (patch faces highlighted), region (faces handed to
        refinement highlighted), refined (new faces highlighted), faired (the result)."""
        nof = np.zeros((0, 3), dtype=np.int64)
        q, f, rf = self.quad_mesh, self.filled, self.refined
        fixed = int((~self.region).sum())
        refined_mask = np.r_[np.zeros(fixed, bool), np.ones(len(rf.faces) - fixed, bool)]
        return [
            Stage("points", self.samples.points, nof),
            Stage("quads", q.vertices, q.faces),
            Stage("holes", q.vertices, q.faces, loops=tuple(self.loops)),
            Stage("filled", f.vertices, f.faces, highlight=self.filled_patch),
            Stage("region", f.vertices, f.faces, highlight=self.region),
            Stage("refined", rf.vertices, rf.faces, highlight=refined_mask),
            Stage("faired", self.faired.vertices, self.faired.faces, highlight=refined_mask),
        ]

    def report(self) -> dict:
        p = self.params
        return {
            "object": self.obj.name,
            "params": {k: getattr(p, k) for k in p.__dataclass_fields__},
            "points": int(len(self.samples.points)),
            "columns": int(len(self.samples.columns)),
            "interval_evaluations": self.samples.interval_evaluations,
            "point_evaluations": self.samples.point_evaluations,
            "quads": int(len(self.linked.quads)),
            "quads_dropped": self.linked.dropped,
            "holes": len(self.loops),
            "hole_sizes": sorted((int(len(lp)) for lp in self.loops), reverse=True),
            "region_faces": int(self.region.sum()),
            "splits": self.splits,
            "flips": self.flips,
            "improve_flips": self.improve_flips,
            "metrics": self.metrics.as_dict(),
            "timings": dict(self.timings),
        }


def _compact(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> Mesh:
    """Drop the vertices no face uses (points the linking left out)."""
    used = np.unique(faces)
    remap = np.full(len(vertices), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return Mesh(vertices[used], remap[faces])


def _side_faces(vertices: NDArray[np.float64], faces: NDArray[np.int64], slope: float) -> NDArray[np.bool_]:
    """Faces whose projection on the camera plane (xy) has zero area (|n_z| <= slope)."""
    n = face_cross(vertices, faces)
    ln = np.linalg.norm(n, axis=1)
    return np.abs(n[:, 2]) <= slope * np.maximum(ln, 1e-300)


def _merge_region(faces: NDArray[np.int64], patch: NDArray[np.bool_], side: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The patches plus the side faces connected to them through side faces (spec §4)."""
    cand = patch | side
    idx = np.flatnonzero(cand)
    if not len(idx):
        return cand
    sub = faces[idx]
    pairs = face_adjacency(sub, manifold_only=False)
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(idx), len(idx)))
    _, lab = connected_components(g, directed=False)
    has_patch = np.zeros(lab.max() + 1, dtype=bool)
    has_patch[lab[patch[idx]]] = True
    out = np.zeros(len(faces), dtype=bool)
    out[idx[has_patch[lab]]] = True
    return out


def triangulate_object(obj: FRepObject, params: FrepParams | None = None, **kw: object) -> FrepResult:
    from ..darning import darn, fair, merge_copies, refine  # the shared darning implementation

    params = params or FrepParams(**kw)  # type: ignore[arg-type]
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    s = sample(obj, SamplingParams(params.qlev, params.blev))
    timings["sampling"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    linked = link(s, obj, diagonal=params.diagonal)
    quad_mesh = _compact(s.points, linked.faces)
    timings["linking"] = time.perf_counter() - t0
    # ---- holes: loops of one-face edges, filled by Liepa's minimum-weight triangulation
    t0 = time.perf_counter()
    V, F = np.asarray(quad_mesh.vertices), np.asarray(quad_mesh.faces)
    loops = boundary_loops(F)
    # darn() only looks at the faces around the loop: hand it those that touch any hole border
    on_loop = np.zeros(len(V), dtype=bool)
    if loops:
        on_loop[np.concatenate(loops)] = True
    near = F[on_loop[F].any(axis=1)]
    done = [darn(V, near, lp, method="liepa", weight=params.weight) for lp in loops]
    merged = [p.merged for p in done if len(p.merged)]  # a pinched loop joins coincident vertices (darning)
    if merged:
        F = merge_copies(F, np.vstack(merged))
    pf = np.vstack([F, *(p.faces for p in done)]) if done else F
    filled = Mesh(V, pf)
    filled_patch = np.r_[np.zeros(len(F), bool), np.ones(len(pf) - len(F), bool)]
    timings["filling"] = time.perf_counter() - t0
    # ---- merging with the zero-projected-area side faces, refinement
    t0 = time.perf_counter()
    region = _merge_region(pf, filled_patch, _side_faces(V, pf, params.side_slope)) if params.merge_sides \
        else filled_patch.copy()
    splits = flips = 0
    if params.refine and region.any():
        # the fixed faces that touch the region are all refinement needs (the border's edge
        # lengths l(v), and the edges a flip must not duplicate)
        touch = np.zeros(len(V), dtype=bool)
        touch[pf[region].ravel()] = True
        ring = pf[~region & touch[pf].any(axis=1)]
        r = refine(V, ring, pf[region], density=params.density)
        RV, RF = r.vertices, np.vstack([pf[~region], r.faces])
        splits, flips = r.splits, r.flips
    else:
        RV, RF = V, pf
    refined = Mesh(RV, RF)
    new = np.r_[np.zeros(len(V), bool), np.ones(len(RV) - len(V), bool)]
    timings["refinement"] = time.perf_counter() - t0
    # ---- fairing: U2 = 0 for the new vertices, the rest fixed
    t0 = time.perf_counter()
    FV = RV
    if params.fairing != "none" and new.any():
        FV = fair(RV, RF, np.flatnonzero(new), operator=params.fairing)
    if params.project and new.any():
        # Fairing cannot know F: over a merged region that wraps round the object (a tube's wall,
        # say) U2 = 0 pulls the wall in like a soap film. Fairing is there to bring the new
        # vertices nearer the curved surface; for each connected group of new vertices that it
        # took farther from F = 0 (summed |F|/|grad F|), the projection starts from the refined
        # (flat) positions instead.
        FV = FV.copy()
        idx = np.flatnonzero(new)
        gain = first_order_distance(obj, FV[idx]) - first_order_distance(obj, RV[idx])
        e = edge_table(RF).edges
        e = e[new[e[:, 0]] & new[e[:, 1]]]
        g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(len(RV), len(RV)))
        _, lab = connected_components(g, directed=False)
        worse = np.bincount(lab[idx], weights=gain, minlength=lab.max() + 1) > 0
        start = np.where(worse[lab][:, None], RV, FV)
        FV[new] = project(obj, start[new])
    faired_faces = RF
    timings["fairing"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    improve_flips = 0
    if params.smooth:  # (choice) isotropic improvement: valence flips + tangential CVT relaxation on F = 0
        FV, faired_faces, improve_flips = improve(obj, FV, RF, rounds=params.smooth)
    faired = Mesh(FV, faired_faces)
    timings["improvement"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    metrics = measure(obj, faired, voxel=float(obj.size[:2].max()) / 2**params.qlev)
    timings["metrics"] = time.perf_counter() - t0
    timings["total"] = sum(v for k, v in timings.items() if k != "metrics")
    return FrepResult(obj, params, s, linked, quad_mesh, loops, filled, filled_patch, region, refined, new,
                      faired, metrics, timings, splits, flips, improve_flips)

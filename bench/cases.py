"""Repair benchmark cases: incomplete meshes with their ground truth.

The five demo cases (algorithms.cases.demo_cases, the same generator as assets/repair), cases cut
from the shared models (../shared/data: fandisk, torus, featuretype, the closed bunny) and the real
scanned bunny, which has no truth (scored on topology only). Every cut is deterministic; the
expected shape of each cut (islands, boundary loops) is checked when it is made, so a change of a
model file cannot silently change a case.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from algorithms import cases as gen
from algorithms.io import load_raw
from algorithms.mesh import Mesh
from algorithms.topology import boundary_loops, islands

DATA = Path(os.environ.get("BRIDGEFIELD_DATA", Path(__file__).resolve().parents[1].parent / "shared" / "data"))


@dataclass(frozen=True, eq=False)
class BenchCase:
    """vertices/faces: the incomplete mesh as a peer gets it; free_points: (P, 3) (given to the
    tools that take points); truth: the closed mesh it was cut from (None for a real scan);
    genus: the genus a right repair has."""

    name: str
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    free_points: NDArray[np.float64]
    truth: Mesh | None
    genus: int
    description: str


def _from_case(c: gen.Case, genus: int, islands_: int | None = None, loops: int | None = None) -> BenchCase:
    m = c.incomplete
    if islands_ is not None or loops is not None:
        n, _ = islands(m.faces)
        nl = len(boundary_loops(m.faces))
        if (islands_ is not None and n != islands_) or (loops is not None and nl != loops):
            raise RuntimeError(f"case {c.name}: expected {islands_} islands / {loops} loops, got {n} / {nl}")
    return BenchCase(c.name, np.asarray(m.vertices), np.asarray(m.faces), np.asarray(c.free_points), c.truth,
                     genus, c.description)


def ball(mesh: Mesh, center: NDArray[np.float64], radius: float) -> NDArray[np.bool_]:
    """Faces whose centroid lies within ``radius`` of ``center``."""
    c = gen.face_centroids(mesh)
    return np.linalg.norm(c - np.asarray(center, dtype=np.float64), axis=1) < radius


def slab(mesh: Mesh, normal: NDArray[np.float64], offset: float, width: float) -> NDArray[np.bool_]:
    """Faces whose centroid lies within width/2 of the plane n.x = offset."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    return np.abs(gen.face_centroids(mesh) @ n - offset) < width / 2


def surface_point(mesh: Mesh, direction: NDArray[np.float64]) -> NDArray[np.float64]:
    """The vertex farthest along ``direction`` from the centroid (a point on the outer surface)."""
    c = mesh.vertices.mean(axis=0)
    d = np.asarray(direction, dtype=np.float64)
    return mesh.vertices[np.argmax((mesh.vertices - c) @ d)]


def load(name: str) -> Mesh:
    v, f = load_raw(DATA / name)
    return Mesh(v, f)


def crease_point(mesh: Mesh, *, min_angle: float = 40.0) -> NDArray[np.float64]:
    """The midpoint of the sharp edge (dihedral above min_angle) nearest the model's centroid."""
    from algorithms.topology import face_adjacency

    fn = mesh.face_normals()
    pairs = face_adjacency(mesh.faces)
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", fn[pairs[:, 0]], fn[pairs[:, 1]]), -1, 1)))
    sharp = pairs[ang > min_angle]
    c = gen.face_centroids(mesh)
    mids = (c[sharp[:, 0]] + c[sharp[:, 1]]) / 2
    return mids[np.argmin(np.linalg.norm(mids - mesh.vertices.mean(axis=0), axis=1))]


def shared_cases() -> list[BenchCase]:
    """Cases cut from ../shared/data (skipped, with a message, when the folder is absent)."""
    if not DATA.exists():
        print(f"[cases] {DATA} not found: shared-data cases skipped")
        return []
    out: list[BenchCase] = []
    fan = load("fandisk.obj")
    d = fan.bbox_diagonal()
    out.append(_from_case(gen.cut(fan, ball(fan, crease_point(fan), 0.1 * d), name="fandisk-crease",
                                  description="fandisk: a hole across a sharp crease (10 % of the diagonal)",
                                  free_points=60, seed=5), 0, 1, 1))
    holes = ball(fan, surface_point(fan, [0.2, 1, 0.3]), 0.05 * d) | ball(fan, surface_point(fan, [-1, -0.2, 0.4]),
                                                                           0.06 * d)
    out.append(_from_case(gen.cut(fan, holes, name="fandisk-holes",
                                  description="fandisk: two holes on its outer faces"), 0, 1, 2))
    tor = load("torus.stl")
    out.append(_from_case(gen.cut(tor, gen.torus_slab(tor, 25.0), name="torus-cut",
                                  description="torus.stl cut across its tube (a lost handle)"), 1, 1, 2))
    th = ball(tor, surface_point(tor, [0.3, 1, 0.5]), 0.2) | ball(tor, surface_point(tor, [-1, -0.1, -0.4]), 0.25)
    out.append(_from_case(gen.cut(tor, th, name="torus-holes", description="torus.stl with two holes"), 1, 1, 2))
    ft = load("featuretype.stl")
    fd = ft.bbox_diagonal()
    fh = ball(ft, surface_point(ft, [0.1, 0.2, 1]), 0.12 * fd) | ball(ft, surface_point(ft, [1, 0.3, 0.2]), 0.108 * fd)
    out.append(_from_case(gen.cut(ft, fh, name="featuretype-hole",
                                  description="featuretype (genus 9): a hole across its top and a side"), 9, 1, 1))
    bun = load("bunny_closed.ply")
    c = bun.vertices.mean(axis=0)
    bd = bun.bbox_diagonal()
    isl = slab(bun, [0, 1, 0], c[1], 0.025 * bd) | slab(bun, [1, 0, 0.3], float(c @ np.array([1, 0, 0.3])), 0.025 * bd)
    out.append(_from_case(gen.cut(bun, isl, name="bunny-islands", free_points=300, jitter=0.0005, seed=9,
                                  description="the closed bunny cut into five islands by two crossing bands, free "
                                              "points in the bands"), 0, 5, 6))
    bh = ball(bun, surface_point(bun, [1, -0.3, 0.1]), 0.07 * bd) \
        | ball(bun, surface_point(bun, [0, 0, 1]), 0.06 * bd) | ball(bun, surface_point(bun, [-1, 0, 0]), 0.06 * bd)
    out.append(_from_case(gen.cut(bun, bh, name="bunny-holes",
                                  description="the closed bunny with three holes on its body (radius 6-7 % of "
                                              "the diagonal)"), 0, 1, 3))
    rng = np.random.default_rng(7)
    many = np.zeros(bun.n_faces, dtype=bool)
    for vi in rng.choice(bun.n_vertices, 60, replace=False):
        many |= ball(bun, bun.vertices[vi], 0.03 * bd)
    out.append(_from_case(gen.cut(bun, many, name="bunny-many-holes",
                                  description="the closed bunny with 60 overlapping small holes (about 2,000 boundary "
                                              "points, the size of the paper's Bunny-1; three tiny fragments)"),
                          0, 4, 44))
    return out


def real_bunny() -> BenchCase | None:
    p = DATA / "bunny.ply"
    if not p.exists():
        return None
    v, f = load_raw(p)
    used = np.zeros(len(v), dtype=bool)
    used[f.ravel()] = True
    return BenchCase("bunny-scan", v, f, v[~used], None, 0,
                     "the scanned bunny as stored: 5 natural holes at the base, duplicate fragments (no truth)")


def all_cases() -> list[BenchCase]:
    demo = [(c, g) for c, g in zip(gen.demo_cases(), (0, 0, 1, 0, 0))]
    out = [_from_case(c, g) for c, g in demo]
    out += shared_cases()
    rb = real_bunny()
    if rb is not None:
        out.append(rb)
    return out

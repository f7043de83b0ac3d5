"""Repair cases with a known answer: closed meshes and ways of cutting them.

A case is an incomplete model made by removing faces from a closed mesh (the ground truth),
optionally with free points sampled (and jittered) on the removed part. Used by the demo assets
(assets/repair/make_demos.py), the tests and the benchmarks, so that every case can be rebuilt.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .mesh import Mesh
from .metrics import sample_surface


@dataclass(frozen=True, eq=False)
class Case:
    """An incomplete model cut from a closed truth mesh.

    incomplete: kept faces over the truth's vertices, unreferenced vertices removed (free
    points are appended after the surface vertices); free_points: (P, 3).
    """

    name: str
    incomplete: Mesh
    free_points: NDArray[np.float64]
    truth: Mesh
    description: str


def icosphere(subdivisions: int = 4, radius: float = 1.0) -> Mesh:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return Mesh(s.vertices, s.faces)


def ellipsoid(axes: tuple[float, float, float] = (1.4, 1.0, 0.9), subdivisions: int = 4) -> Mesh:
    s = icosphere(subdivisions)
    return Mesh(s.vertices * np.asarray(axes), s.faces)


def torus(major: float = 1.0, minor: float = 0.35, major_sections: int = 64, minor_sections: int = 24) -> Mesh:
    """A closed torus around z, faces wound outward (genus 1)."""
    i, j = np.meshgrid(np.arange(major_sections), np.arange(minor_sections), indexing="ij")
    u = 2 * np.pi * i / major_sections
    v = 2 * np.pi * j / minor_sections
    r = major + minor * np.cos(v)
    pts = np.stack([r * np.cos(u), r * np.sin(u), minor * np.sin(v)], axis=-1).reshape(-1, 3)
    idx = lambda a, b: (a % major_sections) * minor_sections + (b % minor_sections)  # noqa: E731
    a, b = i.ravel(), j.ravel()
    q0, q1, q2, q3 = idx(a, b), idx(a + 1, b), idx(a + 1, b + 1), idx(a, b + 1)
    faces = np.vstack([np.stack([q0, q1, q2], 1), np.stack([q0, q2, q3], 1)])
    return Mesh(pts, faces)


def trefoil_tube(n: int = 240, sides: int = 20, radius: float = 0.35) -> Mesh:
    """A tube of radius ``radius`` around the trefoil knot (sin t + 2 sin 2t, cos t - 2 cos 2t,
    -sin 3t), ``n`` rings of ``sides`` vertices, faces wound outward: genus 1, knotted."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    c = np.c_[np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]
    tangent = np.roll(c, -1, axis=0) - np.roll(c, 1, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    side = np.cross(tangent, [0.0, 0.0, 1.0])  # the knot's tangent is never vertical
    side /= np.linalg.norm(side, axis=1)[:, None]
    up = np.cross(tangent, side)
    a = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    v = c[:, None] + radius * (np.cos(a)[None, :, None] * side[:, None] + np.sin(a)[None, :, None] * up[:, None])
    i, j = np.meshgrid(np.arange(n), np.arange(sides), indexing="ij")
    p, q = i * sides + j, i * sides + (j + 1) % sides
    r, s = ((i + 1) % n) * sides + j, ((i + 1) % n) * sides + (j + 1) % sides
    f = np.vstack([np.stack([p, r, q], -1).reshape(-1, 3), np.stack([q, r, s], -1).reshape(-1, 3)])
    tri = v.reshape(-1, 3)[f]
    if np.einsum("ij,ij->", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) < 0:  # six times the volume
        f = f[:, ::-1]
    return Mesh(v.reshape(-1, 3), f)


def star_prism(points: int = 5, inner: float = 0.45, height: float = 0.5, subdivisions: int = 2) -> Mesh:
    """A star of ``points`` points (outer radius 1, inner ``inner``) extruded ``height`` along z,
    faces wound outward, each split in four ``subdivisions`` times: flat faces and sharp edges only,
    convex and concave ones."""
    m = 2 * points
    ang = 2 * np.pi * np.arange(m) / m
    rad = np.where(np.arange(m) % 2 == 0, 1.0, inner)
    ring = np.c_[rad * np.cos(ang), rad * np.sin(ang)]
    v = np.vstack([[0, 0, 0], np.c_[ring, np.zeros(m)], [0, 0, height], np.c_[ring, np.full(m, height)]])
    f = []
    for i in range(m):
        j = (i + 1) % m
        f += [[0, 1 + j, 1 + i], [m + 1, m + 2 + i, m + 2 + j],  # bottom, top
              [1 + i, 1 + j, m + 2 + j], [1 + i, m + 2 + j, m + 2 + i]]  # side
    import trimesh

    prism = subdivided(trimesh.Trimesh(np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64), process=False),
                       subdivisions)
    return Mesh(prism.vertices, prism.faces)


def plate(extents: tuple[float, float, float] = (3.0, 2.0, 0.12), subdivisions: int = 5) -> Mesh:
    """A thin box (trimesh's ``creation.box``), each face split in four ``subdivisions`` times: a
    sheet whose two sides a ball cut removes together."""
    import trimesh

    box = subdivided(trimesh.creation.box(extents), subdivisions)
    return Mesh(box.vertices, box.faces)


def subdivided(mesh, times: int):
    """A ``trimesh.Trimesh`` with each face split in four at its edge midpoints ``times`` times
    (``Trimesh.subdivide``)."""
    for _ in range(times):
        mesh = mesh.subdivide()
    return mesh


def disk(center: tuple[float, float, float] = (0.0, 0.0, 0.0), radius: float = 1.0, *, segments: int = 64,
         rings: int = 4, flip: bool = False) -> Mesh:
    """A flat disk in the plane z = center[2], faces wound counter-clockwise seen from +z
    (normal +z), or from -z if ``flip``. Boundary vertex k sits at angle 2 pi k / segments."""
    pts = [np.zeros(3)]
    faces = []
    for r in range(1, rings + 1):
        ang = 2 * np.pi * np.arange(segments) / segments
        rad = radius * r / rings
        pts.extend(np.stack([rad * np.cos(ang), rad * np.sin(ang), np.zeros(segments)], 1))
    def ring(r: int, k: int) -> int:
        return 0 if r == 0 else 1 + (r - 1) * segments + k % segments
    for k in range(segments):
        faces.append((0, ring(1, k), ring(1, k + 1)))
        for r in range(1, rings):
            a, b, c, d = ring(r, k), ring(r + 1, k), ring(r + 1, k + 1), ring(r, k + 1)
            faces.append((a, b, c))
            faces.append((a, c, d))
    f = np.asarray(faces, dtype=np.int64)
    if flip:
        f = f[:, ::-1]
    return Mesh(np.asarray(pts) + np.asarray(center, dtype=np.float64), f)


def combine(*meshes: Mesh) -> Mesh:
    """One mesh holding all the given meshes (vertex indices offset)."""
    vs, fs, off = [], [], 0
    for m in meshes:
        vs.append(m.vertices)
        fs.append(m.faces + off)
        off += m.n_vertices
    return Mesh(np.vstack(vs), np.vstack(fs))


def cut(truth: Mesh, remove: NDArray[np.bool_], *, name: str, description: str,
        free_points: int = 0, jitter: float = 0.0, seed: int = 0) -> Case:
    """Remove the faces where ``remove`` is True; sample free points on the removed part."""
    keep = ~np.asarray(remove, dtype=bool)
    f = truth.faces[keep]
    used = np.unique(f)
    remap = np.full(truth.n_vertices, -1)
    remap[used] = np.arange(len(used))
    pts = np.zeros((0, 3))
    if free_points and (~keep).any():
        pts = sample_surface(truth.vertices, truth.faces[~keep], free_points, seed=seed)
        if jitter:
            rng = np.random.default_rng(seed + 1)
            pts = pts + rng.normal(scale=jitter, size=pts.shape)
    return Case(name, Mesh(truth.vertices[used], remap[f]), pts, truth, description)


def face_centroids(mesh: Mesh) -> NDArray[np.float64]:
    return mesh.vertices[mesh.faces].mean(axis=1)


def cap(mesh: Mesh, direction: NDArray[np.float64], angle_deg: float) -> NDArray[np.bool_]:
    """Faces whose centroid direction (from the origin) lies within angle_deg of direction."""
    c = face_centroids(mesh)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    cosang = (c @ d) / np.linalg.norm(c, axis=1)
    return cosang > np.cos(np.radians(angle_deg))


def band(mesh: Mesh, axis: int, lo: float, hi: float) -> NDArray[np.bool_]:
    c = face_centroids(mesh)[:, axis]
    return (c > lo) & (c < hi)


def torus_slab(mesh: Mesh, angle_deg: float) -> NDArray[np.bool_]:
    """Faces of a torus around z within +-angle_deg/2 of the +x half-plane: a cut across the tube."""
    c = face_centroids(mesh)
    ang = np.degrees(np.arctan2(c[:, 1], c[:, 0]))
    return np.abs(ang) < angle_deg / 2


def demo_cases() -> list[Case]:
    """The bundled repair demos (assets/repair)."""
    ell = ellipsoid()
    sph = icosphere(4)
    tor = torus()
    return [
        cut(ell, band(ell, 2, -0.12, 0.12), name="two-caps", free_points=40, jitter=0.004, seed=3,
            description="ICM3: two caps of an ellipsoid separated by a band, jittered free points in the band"),
        cut(sph, cap(sph, [0.3, -0.4, 1.0], 62.0), name="big-hole",
            description="ICM2: a sphere with one large curved hole"),
        cut(tor, torus_slab(tor, 22.0), name="cut-torus",
            description="ICMT: a torus with a cut across its tube (a lost handle)"),
        cut(sph, cap(sph, [1, 0.2, 0.1], 14.0) | cap(sph, [-0.5, 0.3, -1.0], 12.0), name="two-holes",
            description="ICM1: a sphere with two small holes"),
        cut(ell, band(ell, 2, -0.12, 0.12) | band(ell, 0, -0.10, 0.10), name="four-islands",
            description="ICM3: an ellipsoid cut into four islands by two crossing bands"),
    ]


CaseMaker = Callable[[], Case]

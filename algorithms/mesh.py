"""The data model: a triangle mesh and an incomplete model (mesh + free points).

Both are frozen dataclasses holding read-only numpy arrays. Derived data (edges, loops,
islands, frames) is computed by functions in :mod:`algorithms.topology` and
:mod:`algorithms.boundary`, never stored twice.

Shapes use the same letters everywhere: V vertices, F faces, P free points.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray


class MeshError(ValueError):
    """Input that cannot form a mesh (bad shapes, NaN coordinates, indices out of range)."""


def face_cross(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(F, 3) (v1 - v0) x (v2 - v0) of each face: its normal by the right-hand rule, of length
    twice its area. The one place the package's face normals and areas come from."""
    t = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
    return np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])


def face_normals(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(F, 3) unit normals by the right-hand rule (zero for degenerate faces)."""
    n = face_cross(vertices, faces)
    ln = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, ln, out=np.zeros_like(n), where=ln > 0)


def face_areas(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(F,) areas."""
    return 0.5 * np.linalg.norm(face_cross(vertices, faces), axis=1)


def _frozen(a: NDArray, dtype: type) -> NDArray:
    out = np.array(a, dtype=dtype, copy=True)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh.

    vertices: (V, 3) float64, finite.
    faces: (F, 3) int64, indices into ``vertices``.
    Vertices no face references are allowed (they are the free points of an incomplete model).
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 3) if np.size(self.vertices) else np.zeros((0, 3))
        f = np.asarray(self.faces).reshape(-1, 3) if np.size(self.faces) else np.zeros((0, 3), dtype=np.int64)
        if not np.all(np.isfinite(v)):
            bad = int(np.flatnonzero(~np.isfinite(v).all(axis=1))[0])
            raise MeshError(f"vertex {bad} has a NaN or infinite coordinate")
        if f.size and not np.issubdtype(f.dtype, np.integer):
            if not np.all(np.equal(np.mod(f, 1), 0)):
                raise MeshError("face indices must be integers")
        f = f.astype(np.int64)
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            raise MeshError(f"face index out of range: faces use {f.min()}..{f.max()} but there are {len(v)} vertices")
        object.__setattr__(self, "vertices", _frozen(v, np.float64))
        object.__setattr__(self, "faces", _frozen(f, np.int64))

    @property
    def n_vertices(self) -> int:
        return int(len(self.vertices))

    @property
    def n_faces(self) -> int:
        return int(len(self.faces))

    def referenced(self) -> NDArray[np.bool_]:
        """(V,) bool: the vertices some face uses."""
        used = np.zeros(len(self.vertices), dtype=bool)
        used[self.faces.ravel()] = True
        return used

    def face_normals(self) -> NDArray[np.float64]:
        """(F, 3) unit normals by the right-hand rule (zero for degenerate faces)."""
        return face_normals(self.vertices, self.faces)

    def face_areas(self) -> NDArray[np.float64]:
        return face_areas(self.vertices, self.faces)

    def bbox_diagonal(self) -> float:
        if not len(self.vertices):
            return 0.0
        return float(np.linalg.norm(self.vertices.max(axis=0) - self.vertices.min(axis=0)))


@dataclass(frozen=True)
class SetAside:
    """A face of the input that normalisation did not keep, and why."""

    face: int  # index of the face in the input file
    vertices: tuple[int, int, int]  # its vertex indices in the input file
    reason: str


@dataclass(frozen=True, eq=False)
class Icadm:
    """An incomplete model (ICADM, spec/repair.md §1): islands of correct triangles + free points.

    mesh: the kept faces over the input's vertices. Vertex numbers are those of the input file
        (plus copies appended at the end where a non-manifold vertex was split; ``vertex_origin``
        maps every vertex to the input vertex it stands for).
    face_origin: (F,) index of each kept face in the input file.
    free_points: (P, 3) points that belong to no triangle (unreferenced vertices, vertices of
        set-aside faces no kept face uses, and an optional separate point cloud).
    free_origin: (P,) for each free point the input vertex it was (-1: from a point cloud).
    set_aside: the input faces not kept, each with its reason.
    flipped: (F,) bool, True where a kept face's winding was reversed to orient its island.
    """

    mesh: Mesh
    free_points: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    face_origin: NDArray[np.int64] | None = None
    vertex_origin: NDArray[np.int64] | None = None
    free_origin: NDArray[np.int64] | None = None
    set_aside: tuple[SetAside, ...] = ()
    flipped: NDArray[np.bool_] | None = None
    source: str = ""

    def __post_init__(self) -> None:
        p = np.asarray(self.free_points, dtype=np.float64).reshape(-1, 3)
        if not np.all(np.isfinite(p)):
            raise MeshError("a free point has a NaN or infinite coordinate")
        object.__setattr__(self, "free_points", _frozen(p, np.float64))
        fr = np.full(len(p), -1) if self.free_origin is None else self.free_origin
        if len(fr) != len(p):
            raise MeshError("free_origin must match free_points")
        object.__setattr__(self, "free_origin", _frozen(fr, np.int64))
        nf = self.mesh.n_faces
        fo = np.arange(nf) if self.face_origin is None else self.face_origin
        vo = np.arange(self.mesh.n_vertices) if self.vertex_origin is None else self.vertex_origin
        fl = np.zeros(nf, dtype=bool) if self.flipped is None else self.flipped
        if len(fo) != nf or len(fl) != nf or len(vo) != self.mesh.n_vertices:
            raise MeshError("face_origin, flipped and vertex_origin must match the mesh")
        object.__setattr__(self, "face_origin", _frozen(fo, np.int64))
        object.__setattr__(self, "vertex_origin", _frozen(vo, np.int64))
        object.__setattr__(self, "flipped", _frozen(fl, np.bool_))

    def free_point_counts(self) -> dict[str, int]:
        """How many free points came from where: unreferenced file vertices, vertices of
        set-aside faces, a separate point cloud."""
        assert self.free_origin is not None
        from_file = self.free_origin >= 0
        unref = np.ones(self.mesh.n_vertices, dtype=bool)
        for s in self.set_aside:
            unref[list(s.vertices)] = False
        orig_unref = from_file.copy()
        orig_unref[from_file] = unref[self.free_origin[from_file]]
        return {"total": int(len(self.free_points)), "unreferenced": int(orig_unref.sum()),
                "from_set_aside_faces": int((from_file & ~orig_unref).sum()),
                "point_cloud": int((~from_file).sum())}

"""Boundary geometry of an incomplete model (spec/repair.md §2) and its summary by island.

For every boundary vertex O: tau_O (unit tangent, positive direction), n_O (external normal,
area weighted), b_O = tau_O x n_O (outward, into the gap) and h_O (charge).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .mesh import Icadm, Mesh, face_cross
from .topology import boundary_loops, edge_table, euler_characteristic, genus, islands


def _unit(a: NDArray[np.float64]) -> NDArray[np.float64]:
    n = np.linalg.norm(a, axis=-1, keepdims=True)
    return np.divide(a, n, out=np.zeros_like(a), where=n > 0)


def vertex_normals(mesh: Mesh) -> NDArray[np.float64]:
    """(V, 3) unit area-weighted vertex normals (zero where no face)."""
    fn = face_cross(mesh.vertices, mesh.faces)  # |fn| = 2 * area: area weighting
    acc = np.zeros_like(mesh.vertices)
    for k in range(3):
        np.add.at(acc, mesh.faces[:, k], fn)
    return _unit(acc)


@dataclass(frozen=True, eq=False)
class LoopFrame:
    """Boundary data of one loop, L = number of loop vertices, in positive order.

    vertices: (L,) vertex indices; points, tangent (tau), normal (n), outward (b): (L, 3);
    charge (h): (L,); island: the island the loop belongs to.
    """

    vertices: NDArray[np.int64]
    points: NDArray[np.float64]
    tangent: NDArray[np.float64]
    normal: NDArray[np.float64]
    outward: NDArray[np.float64]
    charge: NDArray[np.float64]
    island: int

    @property
    def length(self) -> float:
        """Perimeter in model units."""
        return float(np.linalg.norm(np.roll(self.points, -1, axis=0) - self.points, axis=1).sum())


def frame_of(points: NDArray[np.float64], normals: NDArray[np.float64], vertices: NDArray[np.int64], *,
             island: int = -1, charge: str = "length") -> LoopFrame:
    """Frames (spec §2) of a closed walk with the surface on its left (a boundary loop in its
    positive direction, or a hole polygon): tau from the neighbouring edges, n the given surface
    normals, b = tau x n, h per the charge rule.

    charge: "length" (default, spec §2 choice: half the sum of the two boundary edges at O, so
    the field does not change when the boundary is resampled) or "unit" (h = 1).
    """
    p = np.asarray(points, dtype=np.float64)
    e_out = np.roll(p, -1, axis=0) - p  # O -> next
    e_in = p - np.roll(p, 1, axis=0)  # prev -> O
    tau = _unit(_unit(e_in) + _unit(e_out))  # §2: normalised sum of incoming and outgoing directions
    nrm = _unit(np.asarray(normals, dtype=np.float64))
    b = _unit(np.cross(tau, nrm))  # b_O = tau_O x n_O
    if charge == "length":
        h = 0.5 * (np.linalg.norm(e_in, axis=1) + np.linalg.norm(e_out, axis=1))
    elif charge == "unit":
        h = np.ones(len(p))
    else:
        raise ValueError(f"charge must be 'length' or 'unit', not {charge!r}")
    return LoopFrame(np.asarray(vertices, dtype=np.int64), p, tau, nrm, b, h, island)


def loop_frame(mesh: Mesh, loop: NDArray[np.int64], *, island: int = 0,
               normals: NDArray[np.float64] | None = None, charge: str = "length") -> LoopFrame:
    """Frames of one boundary loop of the mesh (walked in the positive direction)."""
    nrm = (vertex_normals(mesh) if normals is None else normals)[loop]
    return frame_of(mesh.vertices[loop], nrm, loop, island=island, charge=charge)


def loop_frames(mesh: Mesh, *, charge: str = "length", labels: NDArray[np.int64] | None = None) -> list[LoopFrame]:
    """Frames of every boundary loop of the mesh, with the island each belongs to (``labels``: the
    faces' island labels when already known, as :func:`algorithms.topology.islands` gives them)."""
    loops = boundary_loops(mesh.faces)
    if not loops:
        return []
    lab = islands(mesh.faces)[1] if labels is None else labels
    vert_island = np.full(mesh.n_vertices, -1, dtype=np.int64)
    vert_island[mesh.faces.ravel()] = np.repeat(lab, 3)
    normals = vertex_normals(mesh)
    return [loop_frame(mesh, lp, island=int(vert_island[lp[0]]), normals=normals, charge=charge) for lp in loops]


@dataclass(frozen=True)
class IslandInfo:
    index: int
    faces: int
    vertices: int
    loops: tuple[int, ...]  # indices into the model's loop list
    euler: int
    genus: float
    area: float


@dataclass(frozen=True)
class ModelSummary:
    islands: tuple[IslandInfo, ...]
    loops: tuple[LoopFrame, ...]
    free_points: int
    class_guess: str

    def as_dict(self) -> dict:
        return {
            "class": self.class_guess,
            "islands": [
                {"index": i.index, "faces": i.faces, "vertices": i.vertices, "loops": list(i.loops),
                 "euler": i.euler, "genus": i.genus, "area": i.area}
                for i in self.islands
            ],
            "loops": [
                {"index": k, "island": lp.island, "vertices": int(len(lp.vertices)), "length": lp.length,
                 "start_vertex": int(lp.vertices[0])}
                for k, lp in enumerate(self.loops)
            ],
            "free_points": self.free_points,
        }


def class_guess(n_islands: int, n_loops: int) -> str:
    """ICM class from the counts (spec §1). Simple vs complex holes are decided by the repair.

    closed: one island, no loop; ICM3: several islands; ICM1/2: one island with holes
    (reported as "ICM2" when it has more than one hole, "ICM1" for a single hole, a guess the
    repair pipeline refines with its simple-hole test).
    """
    if n_islands == 0:
        return "empty"
    if n_islands > 1:
        return "ICM3"
    if n_loops == 0:
        return "closed"
    return "ICM1" if n_loops == 1 else "ICM2"


def summarize(model: Icadm, *, charge: str = "length") -> ModelSummary:
    """Islands, loops, Euler characteristic and genus per island, class guess."""
    mesh = model.mesh
    n, lab = islands(mesh.faces)
    frames = loop_frames(mesh, charge=charge, labels=lab)
    areas = mesh.face_areas()
    infos = []
    for i in range(n):
        fi = mesh.faces[lab == i]
        chi = euler_characteristic(fi)
        lps = tuple(k for k, lp in enumerate(frames) if lp.island == i)
        infos.append(IslandInfo(i, int(len(fi)), int(len(np.unique(fi))), lps, chi,
                                genus(chi, len(lps)), float(areas[lab == i].sum())))
    return ModelSummary(tuple(infos), tuple(frames), int(len(model.free_points)), class_guess(n, len(frames)))


def edge_length_scale(mesh: Mesh) -> float:
    """Mean edge length of the mesh (a natural unit for steps and tolerances)."""
    e = edge_table(mesh.faces).edges
    if not len(e):
        return 0.0
    return float(np.linalg.norm(mesh.vertices[e[:, 0]] - mesh.vertices[e[:, 1]], axis=1).mean())

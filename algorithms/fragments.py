"""Fragments that touch the surface only at a vertex, put back into the repaired surface.

Normalisation sets aside tiny islands that meet the rest of the surface only at a vertex (they
would make that vertex non-manifold, and the field of spec §2 needs manifold loops). On a cut or
scanned surface such a fragment is a piece of the surface left inside a hole, hanging at one vertex
of the hole's border. The repair keeps it: the fragment's boundary loop is walked as part of the
hole, so the hole polygon passes the attachment vertex twice,

    ..., p, m, f1, ..., fk, m, q, ...

(``m`` the hole's vertex, ``f1..fk`` the fragment's boundary loop in its positive direction), the
polygon with the hole on its right everywhere (spec §6: the surface on the left of every walk).
The polygon is then not a disk and the pipeline joins its two sides by a bridge like any walk that
passes a vertex twice, and darns the halves; the fragment's faces become faces of the output with
their vertices unchanged. The fragment's winding follows the surface: it is reversed (recorded)
when its normal disagrees with the surface normal at ``m``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .mesh import Icadm
from .topology import boundary_loops, euler_characteristic, islands, orientation_consistent


@dataclass(frozen=True, eq=False)
class Attached:
    """The fragments put back: hole polygons with the fragments' loops walked in, their faces."""

    polygons: list[tuple[int, ...]]
    faces: NDArray[np.int64]  # (K, 3) the fragments' faces over the model's vertices, output winding
    input_faces: tuple[int, ...] = ()  # the input face of each row of ``faces``
    flipped: tuple[bool, ...] = ()  # True where the winding was reversed to agree with the surface
    normals: dict[int, NDArray[np.float64]] = field(default_factory=dict)  # loop vertex -> fragment normal
    notes: tuple[str, ...] = ()
    source: tuple[int, ...] | None = None  # index of the input polygon each polygon comes from (None: same order)


def _fragments(model: Icadm) -> list[tuple[list[int], NDArray[np.int64]]]:
    """The set-aside fragments, each as (input face ids, faces over input vertices)."""
    ids = [s.face for s in model.set_aside if s.reason.startswith("fragment")]
    if not ids:
        return []
    faces = np.array([next(s.vertices for s in model.set_aside if s.face == i) for i in ids], dtype=np.int64)
    n, lab = islands(faces)
    return [([ids[k] for k in np.flatnonzero(lab == i)], faces[lab == i]) for i in range(n)]


def attach_fragments(model: Icadm, polygons: list[tuple[int, ...]],
                     normals: NDArray[np.float64]) -> Attached:
    """Walk every set-aside fragment that hangs at one vertex of one hole polygon into that polygon.

    polygons: hole polygons (surface on their left). normals: vertex normals of the working
    vertex array (the model's vertices first). A fragment is attached when it is an oriented disk
    (one boundary loop, Euler characteristic 1), exactly one of its vertices is used by the kept
    surface, and that vertex occurs exactly once in all the polygons; others stay set aside (noted).
    """
    polys = [tuple(int(x) for x in p) for p in polygons]
    out_f: list[NDArray[np.int64]] = []
    in_ids: list[int] = []
    flips: list[bool] = []
    nrm_of: dict[int, NDArray[np.float64]] = {}
    notes: list[str] = []
    frags = _fragments(model)
    if not frags:
        return Attached(polys, np.zeros((0, 3), dtype=np.int64), source=tuple(range(len(polys))))
    V = model.mesh.vertices
    origin = model.vertex_origin if model.vertex_origin is not None else np.arange(model.mesh.n_vertices)
    used = np.zeros(len(V), dtype=bool)
    used[np.asarray(origin)[model.mesh.faces.ravel()]] = True
    where: dict[int, list[tuple[int, int]]] = {}  # input vertex -> (polygon, vertex) of each occurrence
    for k, p in enumerate(polys):
        for m in p:
            if m < len(origin):
                where.setdefault(int(origin[m]), []).append((k, m))
    for fids, faces in frags:
        loops = boundary_loops(faces)
        attach = [int(x) for x in np.unique(faces) if used[x]]
        label = f"fragment of face(s) {fids}"
        if len(loops) != 1 or euler_characteristic(faces) != 1 or not orientation_consistent(faces):
            notes.append(f"{label} left aside: not an oriented disk")
            continue
        if len(attach) != 1 or len(where.get(attach[0], [])) != 1:
            notes.append(f"{label} left aside: not hanging at one vertex of one hole")
            continue
        a = attach[0]
        k, m = where[a][0]
        i = polys[k].index(m)
        loop = [int(x) for x in loops[0]]
        if a not in loop:
            notes.append(f"{label} left aside: its attachment vertex is inside it")
            continue
        t = V[faces]
        fn = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]).sum(axis=0)
        flip = bool(fn @ normals[m] < 0)
        if flip:  # reverse the winding: the loop runs the other way
            faces = faces[:, ::-1]
            loop = loop[::-1]
            fn = -fn
        s = loop.index(a)
        walk = loop[s + 1:] + loop[:s]  # f1..fk: the loop after the attachment vertex
        p = polys[k]
        polys[k] = p[:i + 1] + tuple(walk) + (m,) + p[i + 1:]
        out_f.append(np.where(faces == a, m, faces))
        in_ids += fids
        flips += [flip] * len(fids)
        unit = fn / max(float(np.linalg.norm(fn)), 1e-300)
        for x in walk:
            nrm_of[x] = unit
        where.pop(a)  # one fragment per vertex: a second one there would need its own sector
    # fragments that touch each other at a vertex (a chain of fragments across the hole): the walk
    # passes that vertex twice, once on each fragment's loop; the chain cuts the hole in two there
    pieces: list[tuple[int, ...]] = []
    source: list[int] = []
    for k, p in enumerate(polys):
        stack = [p]
        while stack:
            q = stack.pop()
            cut = _pinch(q, nrm_of)
            if cut is None:
                pieces.append(q)
                source.append(k)
            else:
                i, j = cut
                stack += [q[i:j], q[j:] + q[:i]]
    faces_out = np.vstack(out_f) if out_f else np.zeros((0, 3), dtype=np.int64)
    return Attached(pieces, faces_out, tuple(in_ids), tuple(flips), nrm_of, tuple(notes), tuple(source))


def _pinch(polygon: tuple[int, ...], fragment_vertices: dict[int, NDArray[np.float64]]) -> tuple[int, int] | None:
    """Positions (i, j) of the two passes of a fragment vertex the walk passes twice, or None."""
    seen: dict[int, int] = {}
    for k, v in enumerate(polygon):
        if v in fragment_vertices:
            if v in seen:
                return seen[v], k
            seen[v] = k
    return None

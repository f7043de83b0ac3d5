"""Combinatorial topology of a triangle mesh: edges, islands, boundary loops, Euler, genus.

Functions on the face array (F, 3); all vectorised except the walk along a boundary loop, which
is sequential by nature. Half-edges of face (a, b, c) are a->b, b->c, c->a.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import Literal, overload

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components


def halfedges(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    """(3F, 2) directed half-edges; row 3f+k is edge k of face f."""
    f = np.asarray(faces, dtype=np.int64)
    return np.stack([f, np.roll(f, -1, axis=1)], axis=2).reshape(-1, 2)


@dataclass(frozen=True, eq=False)
class EdgeTable:
    """Undirected edges of a face array.

    edges: (E, 2) sorted vertex pairs; halfedge_edge: (3F,) the edge of each half-edge;
    counts: (E,) faces per edge.
    """

    edges: NDArray[np.int64]
    halfedge_edge: NDArray[np.int64]
    counts: NDArray[np.int64]


class VertexFaces:
    """The faces at each vertex, from one stable sort of the face corners: the faces at vertex v are
    ``face_of[start[v]:start[v + 1]]``, ascending (a face with v twice is listed twice)."""

    def __init__(self, faces: NDArray[np.int64], n_vertices: int) -> None:
        flat = np.asarray(faces, dtype=np.int64).ravel()
        self.face_of = np.argsort(flat, kind="stable") // 3
        self.start = np.zeros(n_vertices + 1, dtype=np.int64)
        np.cumsum(np.bincount(flat, minlength=n_vertices), out=self.start[1:])

    def rows(self, v: int) -> NDArray[np.int64]:
        """The faces at vertex ``v``, each once, ascending."""
        return np.unique(self.face_of[self.start[v]:self.start[v + 1]])


_EDGE_CACHE: OrderedDict[tuple, EdgeTable] = OrderedDict()
_EDGE_CACHE_LOCK = threading.Lock()  # the explorer repairs in a worker thread while the GUI asks too
_EDGE_CACHE_SIZE = 8
_EDGE_CACHE_MIN = 3000  # faces: smaller arrays are cheaper to table than to hash


def edge_table(faces: NDArray[np.int64]) -> EdgeTable:
    """The undirected edges of ``faces``. The tables of the last few large face arrays are kept
    (read-only), keyed by the arrays' contents: the repair asks for the edges of the same input
    mesh about fifteen times (bunny-many-holes: 53,000 faces, 17 ms each)."""
    f = np.ascontiguousarray(faces, dtype=np.int64)
    if len(f) < _EDGE_CACHE_MIN:
        return _edge_table(f)
    key = (f.shape, hashlib.blake2b(f.data, digest_size=16).digest())
    with _EDGE_CACHE_LOCK:
        hit = _EDGE_CACHE.get(key)
        if hit is not None:
            _EDGE_CACHE.move_to_end(key)
            return hit
    et = _edge_table(f)
    for a in (et.edges, et.halfedge_edge, et.counts):
        a.flags.writeable = False
    with _EDGE_CACHE_LOCK:
        _EDGE_CACHE[key] = et
        if len(_EDGE_CACHE) > _EDGE_CACHE_SIZE:
            _EDGE_CACHE.popitem(last=False)
    return et


def _edge_table(faces: NDArray[np.int64]) -> EdgeTable:
    he = halfedges(faces)
    if not len(he):
        z = np.zeros((0, 2), dtype=np.int64)
        return EdgeTable(z, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
    und = np.sort(he, axis=1)
    n = int(und.max()) + 1
    # one int64 key per edge: far faster than np.unique over rows
    keys, inv, counts = np.unique(und[:, 0] * n + und[:, 1], return_inverse=True, return_counts=True)
    edges = np.stack([keys // n, keys % n], axis=1)
    return EdgeTable(edges, inv.ravel(), counts)


@overload
def face_adjacency(faces: NDArray[np.int64], *, manifold_only: bool = ...,
                   with_edges: Literal[False] = ...) -> NDArray[np.int64]: ...


@overload
def face_adjacency(faces: NDArray[np.int64], *, manifold_only: bool = ...,
                   with_edges: Literal[True]) -> tuple[NDArray[np.int64], NDArray[np.int64]]: ...


def face_adjacency(faces: NDArray[np.int64], *, manifold_only: bool = True, with_edges: bool = False
                   ) -> NDArray[np.int64] | tuple[NDArray[np.int64], NDArray[np.int64]]:
    """(K, 2) pairs of faces that share an edge (only edges with exactly two faces if manifold_only);
    with ``with_edges`` also (K, 2) the shared edge of each pair (sorted vertex pair)."""
    et = edge_table(faces)
    order = np.argsort(et.halfedge_edge, kind="stable")
    e_sorted = et.halfedge_edge[order]
    face_of = order // 3
    # consecutive half-edges of the same edge
    same = e_sorted[1:] == e_sorted[:-1]
    pairs = np.stack([face_of[:-1][same], face_of[1:][same]], axis=1)
    edge = e_sorted[:-1][same]
    if manifold_only:
        two = et.counts[edge] == 2
        pairs, edge = pairs[two], edge[two]
    return (pairs, et.edges[edge]) if with_edges else pairs


def islands(faces: NDArray[np.int64]) -> tuple[int, NDArray[np.int64]]:
    """Connected components of faces through shared edges: (count, (F,) label).

    Labels are ordered by decreasing size (island 0 is the largest), ties by first face.
    """
    nf = len(faces)
    if nf == 0:
        return 0, np.zeros(0, dtype=np.int64)
    pairs = face_adjacency(faces, manifold_only=False)
    g = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(nf, nf))
    n, lab = connected_components(g, directed=False)
    sizes = np.bincount(lab, minlength=n)
    first = np.full(n, nf)
    np.minimum.at(first, lab, np.arange(nf))
    order = np.lexsort((first, -sizes))
    rank = np.empty(n, dtype=np.int64)
    rank[order] = np.arange(n)
    return int(n), rank[lab]


def boundary_halfedges(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    """(B, 2) half-edges whose edge has exactly one face, directed as in the face's winding.

    With faces wound counter-clockwise seen from outside, this is the positive direction of
    spec/repair.md §2.
    """
    et = edge_table(faces)
    he = halfedges(faces)
    return he[et.counts[et.halfedge_edge] == 1]


def boundary_loops(faces: NDArray[np.int64]) -> list[NDArray[np.int64]]:
    """Boundary loops as vertex index arrays, each walked in its positive direction.

    A loop lists each vertex once; the edge from the last vertex back to the first closes it.
    Where several boundary half-edges leave one vertex (two loops touching at a vertex), the
    walk turns around the vertex through the faces to stay on its own loop. Loops are sorted
    by decreasing length, ties by smallest vertex.
    """
    faces = np.asarray(faces, dtype=np.int64)
    bhe = boundary_halfedges(faces)
    if not len(bhe):
        return []
    nv = int(faces.max()) + 1
    if np.bincount(bhe[:, 0], minlength=nv).max() == 1 and np.bincount(bhe[:, 1], minlength=nv).max() == 1:
        return _simple_loops(bhe, nv)  # one boundary edge leaves and one enters each: disjoint cycles
    return _walk_loops(faces, bhe, nv)


def _walk_loops(faces: NDArray[np.int64], bhe: NDArray[np.int64], nv: int) -> list[NDArray[np.int64]]:
    """boundary_loops' general walk (turning around vertices where several loops touch)."""
    # half-edge lookup by key a*V+b for the fan walk
    he = halfedges(faces)
    keys = he[:, 0] * nv + he[:, 1]
    korder = np.argsort(keys)
    ksorted = keys[korder]

    def face_of(a: int, b: int) -> int:
        k = a * nv + b
        i = np.searchsorted(ksorted, k)
        if i < len(ksorted) and ksorted[i] == k:
            return int(korder[i] // 3)
        return -1

    out_edges: dict[int, list[int]] = {}
    for a, b in bhe.tolist():
        out_edges.setdefault(a, []).append(b)
    bset = {(a, b) for a, b in bhe.tolist()}

    def next_from(prev: int, v: int) -> int:
        outs = out_edges[v]
        if len(outs) == 1:
            return outs[0]
        # fan walk: start in the face of (prev, v), rotate around v until a boundary edge leaves v
        f = face_of(prev, v)
        for _ in range(len(faces)):
            tri = faces[f].tolist()
            k = tri.index(v)
            w = tri[(k + 1) % 3]
            if (v, w) in bset:
                return w
            f = face_of(w, v)
            if f < 0:
                break
        return outs[0]

    used: set[tuple[int, int]] = set()
    loops: list[NDArray[np.int64]] = []
    for a, b in bhe.tolist():
        if (a, b) in used:
            continue
        loop = [a]
        used.add((a, b))
        prev, cur = a, b
        while cur != a:
            loop.append(cur)
            nxt = next_from(prev, cur)
            if (cur, nxt) in used:
                break
            used.add((cur, nxt))
            prev, cur = cur, nxt
        loops.append(np.array(loop, dtype=np.int64))
    loops.sort(key=lambda lp: (-len(lp), int(lp.min())))
    return loops


def _simple_loops(bhe: NDArray[np.int64], nv: int) -> list[NDArray[np.int64]]:
    """boundary_loops where each boundary vertex has one outgoing and one incoming boundary
    half-edge (the loops are disjoint cycles): each loop starts at the first of its half-edges in
    ``bhe``'s order and follows the successors (boundary_loops' walk, without the fan turns it
    never needs here)."""
    nxt = np.full(nv, -1, dtype=np.int64)
    nxt[bhe[:, 0]] = bhe[:, 1]
    succ = nxt.tolist()
    seen = bytearray(nv)
    loops: list[NDArray[np.int64]] = []
    for a in bhe[:, 0].tolist():
        if seen[a]:
            continue
        loop = [a]
        seen[a] = 1
        cur = succ[a]
        while cur != a:
            loop.append(cur)
            seen[cur] = 1
            cur = succ[cur]
        loops.append(np.array(loop, dtype=np.int64))
    loops.sort(key=lambda lp: (-len(lp), int(lp.min())))
    return loops


def euler_characteristic(faces: NDArray[np.int64]) -> int:
    """chi = V - E + F over the vertices the faces use."""
    faces = np.asarray(faces, dtype=np.int64)
    if not len(faces):
        return 0
    nv = len(np.unique(faces))
    ne = len(edge_table(faces).edges)
    return int(nv - ne + len(faces))


def genus(chi: int, n_boundaries: int, n_components: int = 1) -> float:
    """Genus of an orientable surface: chi = 2c - 2g - b  =>  g = (2c - chi - b) / 2."""
    return (2 * n_components - chi - n_boundaries) / 2


def is_closed_manifold(faces: NDArray[np.int64]) -> bool:
    """Every edge has exactly two faces, and they traverse it in opposite directions."""
    faces = np.asarray(faces, dtype=np.int64)
    if not len(faces):
        return False
    et = edge_table(faces)
    if not np.all(et.counts == 2):
        return False
    return orientation_consistent(faces)


def orientation_consistent(faces: NDArray[np.int64]) -> bool:
    """No directed half-edge occurs twice (neighbouring faces wind the same way)."""
    he = halfedges(faces)
    if not len(he):
        return True
    return len(np.unique(he, axis=0)) == len(he)


def nonmanifold_vertices(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    """Vertices whose incident faces form more than one fan (connected through edges at the vertex)."""
    return np.array([v for v, fans in vertex_fans(faces).items() if len(fans) > 1], dtype=np.int64)


def vertex_fans(faces: NDArray[np.int64]) -> dict[int, list[list[int]]]:
    """For every vertex with more than one fan: its fans, as lists of incident face indices.

    Two faces at v are in one fan when they share an edge that has v as an endpoint. The corners
    (face, k) of each vertex are joined across such edges and counted by connected component, so
    two closed fans that touch at a vertex (a pinch of a closed surface) count as two. Vertices
    with a single fan are not listed.
    """
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    faces = np.asarray(faces, dtype=np.int64)
    nf = len(faces)
    if not nf:
        return {}
    pairs = face_adjacency(faces, manifold_only=False)
    corner = np.arange(3 * nf).reshape(nf, 3)
    fa, fb = faces[pairs[:, 0]], faces[pairs[:, 1]]
    rows, cols = [], []
    for ka in range(3):
        for kb in range(3):
            m = fa[:, ka] == fb[:, kb]  # the pair's shared edge passes this vertex
            rows.append(corner[pairs[m, 0], ka])
            cols.append(corner[pairs[m, 1], kb])
    r, c = np.concatenate(rows), np.concatenate(cols)
    g = sp.coo_matrix((np.ones(len(r)), (r, c)), shape=(3 * nf, 3 * nf))
    _, fan = connected_components(g, directed=False)
    vert = faces.ravel()
    # fans per vertex: distinct (vertex, fan) pairs, one int64 key each
    vf = np.unique(vert * (3 * nf) + fan) // (3 * nf)
    many = vf[np.r_[False, vf[1:] == vf[:-1]]]
    groups: dict[int, dict[int, list[int]]] = {}
    at = np.isin(vert, many)
    for v, f, k in zip(vert[at].tolist(), (np.flatnonzero(at) // 3).tolist(), fan[at].tolist()):
        groups.setdefault(v, {}).setdefault(k, []).append(f)
    return {v: list(g.values()) for v, g in groups.items()}

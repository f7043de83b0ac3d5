"""Copies of one point joined into one vertex: the output touches itself nowhere.

Normalisation splits an input vertex where islands or fans of faces meet only at it (a cut that
leaves two holes touching at a corner), and the repair splits a vertex where its patches meet only
at it (:func:`algorithms.repair._split_pinches`). Each copy then has one fan and the output is a
manifold surface as written, but the copies share a position: a tool that merges vertices by
position (the scorer, ``../shared/tools/score_repair.py``, loads the output with trimesh's
``process=True``) sees a vertex with two fans, a changed Euler characteristic and, where both ends
of an edge were copied, an edge with four faces. The surface the input was cut from has one vertex
there with one fan.

**(choice)** The copies are joined by contracting a path of new vertices between them: the edges
``c = p0, p1, ..., pk = k`` (``c`` a copy, ``k`` the vertex kept, p1..pk-1 new vertices of the
patches) are collapsed one after another into ``k``, each only if it passes the link condition
(Dey et al. 1999, "Topology preserving edge contraction": the vertices adjacent to both ends are
exactly the two opposite the edge), which keeps the surface's topology as written: contracting an
arc of a surface is a homeomorphism. A face of the input is never removed (a collapsed edge has a
new vertex at one end at least, so its two faces are patch faces) and never moves (its copy is
renamed to the kept vertex at the same position). The patch faces that met the collapsed vertices
now meet ``k``; the refinement that follows evens them out. Two copies with a neighbour in
common (a patch from one copy's fan to a vertex of the other's) fail the link condition whatever
the path; the patch edge to that neighbour is flipped or split first (:func:`_unshared`).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .topology import edge_table, vertex_fans

# **(choice)** vertices closer than this share of the diagonal are one point (the benchmarks merge
# at the same distance; a fill clamped into a convex corner landed 1e-16 from its input vertex on
# frep-plate3 cut 12:0, which the scorer merges)
COINCIDENT = 1e-6
# **(choice)** at most this many new vertices on a path that joins two copies (the copies of the
# sweep's cuts are two or three edges apart through their patches); a longer path would drag a
# patch's faces far across to the kept vertex
MAX_PATH = 6
UNSHARE = True  # _unshared before giving a copy up (a switch for measuring)


@dataclass(frozen=True)
class Joined:
    """vertices, faces: after the joins (the input's rows first, in their order); joined: copies
    joined into their kept vertex; moved: new vertices that lay on another vertex and could not be
    joined to it, moved off it; left: copies of input vertices that could not be joined (they stay
    separate vertices at the kept one's position); parted: of the joined, those that had to be
    parted from neighbours in common first (:func:`_unshared`)."""

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    joined: int
    moved: int
    left: int
    parted: int = 0


def close_clusters(points: NDArray[np.float64], radius: float) -> NDArray[np.int64]:
    """(N,) a label per point: points joined by a chain of pairs at most ``radius`` apart share one
    (connected components of the k-d tree's pairs). Where no two x coordinates lie that close (a
    sort of one coordinate), every point is its own cluster and no tree is built."""
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n < 2 or np.all(np.diff(np.sort(pts[:, 0])) > radius):
        return np.arange(n, dtype=np.int64)
    pairs = cKDTree(pts).query_pairs(radius, output_type="ndarray")
    if not len(pairs):
        return np.arange(n, dtype=np.int64)
    _, label = connected_components(coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)),
                                    directed=False)
    return label.astype(np.int64)


def coincident_groups(vertices: NDArray[np.float64], faces: NDArray[np.int64], *,
                      tol: float = COINCIDENT) -> list[NDArray[np.int64]]:
    """Groups of two or more vertices of ``faces`` within ``tol`` times the diagonal of their box of
    one another (:func:`close_clusters`), each sorted (the smallest index first: the input's vertex,
    its copies appended after it), in the order of their clusters' labels."""
    mask = np.zeros(len(vertices), dtype=bool)
    mask[np.asarray(faces, dtype=np.int64).ravel()] = True
    used = np.flatnonzero(mask)
    if len(used) < 2:
        return []
    pts = np.asarray(vertices, dtype=np.float64)[used]
    label = close_clusters(pts, tol * float(np.linalg.norm(np.ptp(pts, axis=0))))
    counts = np.bincount(label)
    return [np.sort(used[label == g]) for g in np.flatnonzero(counts > 1)]


class _Star:
    """The faces at each vertex of a surface being contracted (faces as a list of rows; a removed
    face is None)."""

    def __init__(self, faces: NDArray[np.int64]) -> None:
        self.rows: list[list[int] | None] = [list(map(int, r)) for r in faces]
        self.at: dict[int, set[int]] = {}
        for i, r in enumerate(self.rows):
            for v in r:
                self.at.setdefault(v, set()).add(i)

    def neighbours(self, v: int) -> set[int]:
        out: set[int] = set()
        for i in self.at.get(v, ()):
            out.update(self.rows[i])
        out.discard(v)
        return out

    def faces_on(self, u: int, w: int) -> list[int]:
        """The faces that hold the edge (u, w)."""
        return [i for i in self.at.get(u, ()) if w in self.rows[i]]

    def patch_pair(self, u: int, w: int, n_fixed_faces: int) -> tuple[int, int, int, int] | None:
        """(i, j, x, y) for an edge (u, w) between two patch faces (none of the first
        ``n_fixed_faces``) of consistent orientation: face i runs u -> w -> x, face j w -> u -> y;
        None otherwise."""
        both = self.faces_on(u, w)
        if len(both) != 2 or min(both) < n_fixed_faces:
            return None
        i, j = both
        if self.rows[i][(self.rows[i].index(u) + 1) % 3] != w:
            i, j = j, i
        ri, rj = self.rows[i], self.rows[j]
        if ri[(ri.index(u) + 1) % 3] != w or rj[(rj.index(w) + 1) % 3] != u:
            return None  # inconsistent orientation across the edge
        return i, j, ri[(ri.index(u) + 2) % 3], rj[(rj.index(u) + 1) % 3]

    def link_condition(self, u: int, k: int) -> bool:
        """Whether the edge (u, k) has exactly two faces and the vertices adjacent to both ends are
        exactly their third vertices (Dey et al. 1999)."""
        both = self.faces_on(u, k)
        if len(both) != 2:
            return False
        opposite = {v for i in both for v in self.rows[i] if v not in (u, k)}
        return len(opposite) == 2 and self.neighbours(u) & self.neighbours(k) == opposite

    def collapse(self, u: int, k: int) -> None:
        """Contract the edge (u, k) into k: its two faces go, u's other faces meet k."""
        for i in list(self.at.pop(u, ())):
            r = self.rows[i]
            if k in r:
                for v in r:
                    if v != u:
                        self.at[v].discard(i)
                self.rows[i] = None
            else:
                self.rows[i] = [k if v == u else v for v in r]
                self.at[k].add(i)


def _paths(star: _Star, start: int, goal: int, new: NDArray[np.bool_], limit: int) -> list[list[int]]:
    """Shortest paths (breadth first, fewest edges first) from ``start`` to ``goal`` whose inner
    vertices are new ones, with at most ``limit`` inner vertices; a few of each length."""
    out: list[list[int]] = []
    queue: deque[list[int]] = deque([[start]])
    seen_len: dict[int, int] = {start: 0}
    while queue and len(out) < 8:  # sequential: breadth first
        path = queue.popleft()
        if len(path) - 1 > limit:
            break
        for w in sorted(star.neighbours(path[-1])):
            if w == goal:
                out.append(path + [w])
            elif new[w] and w not in path and seen_len.get(w, len(path) + 1) >= len(path):
                seen_len[w] = len(path)
                queue.append(path + [w])
    return out


def _one_fan_each(star: _Star, vs: set[int]) -> bool:
    """Whether every vertex of ``vs`` has one fan of faces (topology.vertex_fans, the definition of
    the report's ``manifold_vertices``) and no edge at it more than two faces."""
    rows = sorted({i for v in vs for i in star.at.get(v, ())})
    f = np.asarray([star.rows[i] for i in rows], dtype=np.int64).reshape(-1, 3)
    et = edge_table(f)
    at = np.isin(et.edges, np.fromiter(vs, dtype=np.int64)).any(axis=1)
    return not (et.counts[at] > 2).any() and not vs & set(vertex_fans(f))


def _copy(star: _Star) -> _Star:
    out = _Star.__new__(_Star)
    out.rows = list(star.rows)
    out.at = {v: set(s) for v, s in star.at.items()}
    return out


def _contract(star: _Star, path: list[int], keep: int, n_fixed_faces: int) -> _Star | None:
    """``star`` with the path (c, p1, ..., keep) contracted into ``keep`` (the last inner vertex
    first), or None where an edge fails the link condition, a face of the first ``n_fixed_faces``
    would go, or a vertex around ``keep`` is left with more than one fan."""
    trial = _copy(star)
    for u in reversed(path[:-1]):
        if not trial.link_condition(u, keep):
            return None
        trial.collapse(u, keep)
    if any(r is None for r in trial.rows[:n_fixed_faces]):
        return None
    touched = trial.neighbours(keep) | {keep}
    return trial if _one_fan_each(trial, touched) else None


def _through_faces(star: _Star, c: int, keep: int, n_fixed_faces: int, limit: int) -> _Star | None:
    """Where no path of new vertices joins ``c`` to ``keep``: a path of patch faces f0 (at keep), ...,
    fn (at c), each next to the one before across an edge of two patch faces (breadth first, at
    most ``limit`` + 1 faces), gets a vertex in each face (a split into three) and the edges between
    consecutive faces flipped, so that those vertices form a path from keep to c; that path is
    contracted (:func:`_contract`). The vertices are never placed: they vanish into ``keep``."""
    def patch(i: int) -> bool:
        return i >= n_fixed_faces and star.rows[i] is not None

    starts = [i for i in star.at.get(keep, ()) if patch(i)]
    goals = {i for i in star.at.get(c, ()) if patch(i)}
    prev: dict[int, int] = {i: -1 for i in starts}
    queue = deque((i, 0) for i in starts)
    end = next((i for i in starts if i in goals), None)
    while queue and end is None:  # sequential: breadth first
        i, d = queue.popleft()
        if d >= limit:
            continue
        r = star.rows[i]
        for k in range(3):
            a, b = r[k], r[(k + 1) % 3]
            across = [j for j in star.at[a] & star.at[b] if j != i]
            if len(across) != 1 or not patch(across[0]) or across[0] in prev:
                continue
            j = across[0]
            prev[j] = i
            if j in goals:
                end = j
                break
            queue.append((j, d + 1))
    if end is None:
        return None
    chain = [end]
    while prev[chain[-1]] >= 0:
        chain.append(prev[chain[-1]])
    chain.reverse()  # f0 at keep ... fn at c
    trial = _copy(star)
    nxt = max(trial.at) + 1
    mids = []
    for i in chain:  # split each face of the chain at a new vertex
        a, b, d = trial.rows[i]
        m = nxt + len(mids)
        mids.append(m)
        trial.rows[i] = [m, a, b]
        trial.rows += [[m, b, d], [m, d, a]]
        n = len(trial.rows)
        trial.at[m] = {i, n - 2, n - 1}
        trial.at[b].add(n - 2)
        trial.at[d].update((n - 2, n - 1))
        trial.at[a].add(n - 1)
        trial.at[d].discard(i)
    for m0, m1 in zip(mids, mids[1:]):  # flip the edge between consecutive faces: m0 - m1
        pair = next(((i, j) for i in trial.at[m0] for j in trial.at[m1]
                     if len(set(trial.rows[i]) & set(trial.rows[j])) == 2), None)  # the faces on the old edge
        if pair is None:
            return None
        i, j = pair
        ri, rj = trial.rows[i], trial.rows[j]
        k = ri.index(m0)
        u, w = ri[(k + 1) % 3], ri[(k + 2) % 3]  # face i = (m0, u, w), face j = (m1, w, u)
        if rj[(rj.index(m1) + 1) % 3] != w:
            return None  # inconsistent orientation across the edge
        trial.rows[i], trial.rows[j] = [m0, u, m1], [m1, w, m0]
        trial.at[w].discard(i)
        trial.at[u].discard(j)
        trial.at[m1].add(i)
        trial.at[m0].add(j)
    return _contract(trial, [c, *reversed(mids), keep], keep, n_fixed_faces)


def _flip(star: _Star, V: NDArray[np.float64], u: int, w: int, n_fixed_faces: int) -> bool:
    """Flip the edge (u, w) in place if both its faces are patch faces (not among the first
    ``n_fixed_faces``), the other diagonal is no edge yet nor of no length (two copies of one point
    joined by an edge cannot be joined into one vertex) and the two new faces keep the side the old
    pair faced (each new normal within 90 degrees of the old pair's summed normal)."""
    pair = star.patch_pair(u, w, n_fixed_faces)
    if pair is None:
        return False
    i, j, x, y = pair
    ri, rj = star.rows[i], star.rows[j]
    if x == y or y in star.neighbours(x) or np.linalg.norm(V[x] - V[y]) <= 1e-6 * np.linalg.norm(V[u] - V[w]):
        return False  # an edge already, or one between two copies of a point (cylinder-sub+speckle 1:0)

    def normal(r: list[int]) -> NDArray[np.float64]:
        return np.cross(V[r[1]] - V[r[0]], V[r[2]] - V[r[0]])

    before = normal(ri) + normal(rj)
    a, b = [u, y, x], [y, w, x]  # the quad u, y, w, x split along y - x, in the old faces' order
    if normal(a) @ before <= 0 or normal(b) @ before <= 0:
        return False
    star.rows[i], star.rows[j] = a, b
    star.at[w].discard(i)
    star.at[y].add(i)
    star.at[u].discard(j)
    star.at[x].add(j)
    return True


def _split(star: _Star, u: int, w: int, m: int, n_fixed_faces: int) -> bool:
    """Split the edge (u, w) in place at a new vertex ``m`` if both its faces are patch faces: each
    of the two faces becomes two, and u and w are no longer next to each other."""
    pair = star.patch_pair(u, w, n_fixed_faces)
    if pair is None:
        return False
    i, j, x, y = pair
    n = len(star.rows)
    star.rows[i], star.rows[j] = [u, m, x], [w, m, y]
    star.rows += [[m, w, x], [m, u, y]]
    star.at[w] = (star.at[w] - {i}) | {n}
    star.at[u] = (star.at[u] - {j}) | {n + 1}
    star.at[x].add(n)
    star.at[y].add(n + 1)
    star.at[m] = {i, j, n, n + 1}
    return True


def _unshared(star: _Star, V: NDArray[np.float64], c: int, keep: int, new: NDArray[np.bool_], n_fixed_faces: int
              ) -> tuple[_Star, NDArray[np.float64]] | None:
    """A copy of ``star`` in which no old vertex is next to both ``c`` and ``keep``, with the
    positions of the vertices it adds (numbered from ``len(V)``), or None if there is no such
    vertex or one cannot be parted from them. A patch that ran from one copy's fan to a vertex of
    the other's gives the two a neighbour in common, and joined, that edge would have four faces
    (mushroom sweep cut 15:1: patch faces from each of two copies to a vertex of the other's input
    fan, one of the two edges between two patch faces). The edge from the copy (or the kept
    vertex) to that neighbour is flipped (:func:`_flip`) where the flip folds nothing, split
    (:func:`_split`) otherwise, its new vertex a quarter of the way from the edge's middle to the
    middle of the two vertices opposite it, inside the patch."""
    shared = [s for s in sorted(star.neighbours(c) & star.neighbours(keep)) if s >= len(new) or not new[s]]
    if not shared:
        return None
    trial = _copy(star)
    pos = V  # with the vertices added so far
    for s in shared:
        if any(_flip(trial, pos, x, s, n_fixed_faces) for x in (c, keep)):
            continue
        for x in (c, keep):
            opposite = [v for i in trial.faces_on(x, s) for v in trial.rows[i] if v not in (x, s)]
            if _split(trial, x, s, len(pos), n_fixed_faces):
                mid = (pos[x] + pos[s]) / 2
                pos = np.vstack([pos, mid + 0.25 * (pos[opposite].mean(axis=0) - mid)])
                break
        else:
            return None
    return trial, pos[len(V):]


def _join(star: _Star, c: int, keep: int, new: NDArray[np.bool_], n_fixed_faces: int, max_path: int
          ) -> _Star | None:
    """``star`` with ``c`` joined into ``keep``: along a path of new vertices (:func:`_contract`), or
    through the patch faces between them (:func:`_through_faces`); None if neither can."""
    for path in _paths(star, c, keep, new, max_path):
        got = _contract(star, path, keep, n_fixed_faces)
        if got is not None:
            return got
    # no path of new vertices: make one through the patch faces between them
    return _through_faces(star, c, keep, n_fixed_faces, max_path)


def join_copies(vertices: NDArray[np.float64], faces: NDArray[np.int64], n_fixed: int, n_fixed_faces: int, *,
                held: NDArray[np.int64] | None = None, max_path: int = MAX_PATH, unshare: bool = True) -> Joined:
    """Join every group of vertices at one position (:func:`coincident_groups`) into its smallest
    index by contracting paths of new vertices (index ``n_fixed`` or more) between them (module
    docstring). A join is kept only if every vertex it touched has one fan afterwards; otherwise
    the copy stays as it was (a new vertex is moved off the point, halfway to the mean of its
    neighbours), and so it does if a join would remove one of the first
    ``n_fixed_faces`` faces (the input's). Copies that no join reaches because they have neighbours
    in common are parted from those first (:func:`_unshared`: patch edges flipped or split; the
    vertices a split adds are appended to the vertices returned; not with ``unshare`` False). Faces
    are returned in their order with the removed ones left out. ``held``: new vertices that must
    stay (crease chains) and so are on no contracted path."""
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    groups = coincident_groups(vertices, F)
    V = np.array(vertices, dtype=np.float64, copy=True)
    if not groups:
        return Joined(V, F.copy(), 0, 0, 0)
    new = np.zeros(max(len(vertices), int(F.max()) + 1), dtype=bool)
    new[n_fixed:] = True
    new[F[:n_fixed_faces].ravel()] = False  # a vertex of an input face never moves (a split pinch's copy is one)
    if held is not None:
        new[np.asarray(held, dtype=np.int64)] = False
    star = _Star(F)
    joined = left = parted = 0
    moved = 0
    for g in groups:  # sequential: each join changes the stars the next one walks
        keep = int(g[0])
        for c in map(int, g[1:]):
            if not star.at.get(c):
                continue  # contracted already, on the path of an earlier copy of this point
            if not new[c] and not np.array_equal(V[c], V[keep]):
                left += 1  # two input vertices almost at one point: joined, an input face would move
                continue
            got = _join(star, c, keep, new, n_fixed_faces, max_path)
            if got is None and UNSHARE and unshare:  # neighbours in common: parted from one of the two first
                un = _unshared(star, V, c, keep, new, n_fixed_faces)
                if un is not None:
                    n_new = np.ones(len(un[1]), dtype=bool)
                    got = _join(un[0], c, keep, np.concatenate([new, n_new]), n_fixed_faces, max_path)
                    if got is not None:
                        V, new = np.vstack([V, un[1]]), np.concatenate([new, n_new])
                        parted += 1
            if got is not None:
                star = got
                joined += 1
            elif new[c]:
                # a new vertex on another one (a fill clamped into a convex corner of the box, on the far
                # side of input faces from it) that no path joins: halfway to the mean of its neighbours,
                # so that the output does not touch itself there
                ring = sorted(star.neighbours(c))
                V[c] += 0.5 * (V[ring].mean(axis=0) - V[c])
                moved += 1
            else:
                left += 1
    rows = [r for r in star.rows if r is not None]
    return Joined(V, np.asarray(rows, dtype=np.int64).reshape(-1, 3), joined, moved, left, parted)

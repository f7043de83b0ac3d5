"""The bridge graph: choosing non-conflicting bridges and extracting the holes they bound.

spec/repair.md §6 step 1. A bridge joins two boundary vertices A and B by a chain of new
vertices (the points of its force line). Candidates conflict when they share an endpoint,
cross or run too close to a kept bridge, or duplicate a connection between the same two loops
in the same neighbourhood; conflicts are resolved by keeping the best quality first.

Holes are extracted by the walking rule: walk each boundary loop in its positive direction; at a
vertex where a bridge starts, take the bridge; on arriving, continue along the arrival loop in
its positive direction. Each bridge is walked once in each direction and each closed walk is a
new hole. A walk that uses one bridge twice bounds a region that is not a disk.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .topology import edge_table

# the kinds of bridge (Bridge.kind), in the order the report and the explorer list them
BRIDGE_KINDS = ("island", "tunnel", "split", "crease", "pinch")


@dataclass(frozen=True, eq=False)
class Bridge:
    """A bridge from boundary vertex ``start`` to boundary vertex ``end``.

    points: (K, 3) the chain's interior points, in order from start to end (may be empty).
    kind: "island" (joins islands), "tunnel" (rebuilds a handle), "split" (splits a hole), "crease"
    (continues a sharp crease across a hole), "pinch" (zero-length: joins two copies of one input
    vertex on the holes, repair._pinch_joins).
    """

    start: int
    end: int
    points: NDArray[np.float64]
    quality: float
    kind: str = "island"
    candidate: int = -1  # index of the candidate line it came from

    def polyline(self, vertices: NDArray[np.float64]) -> NDArray[np.float64]:
        """(K+2, 3) the full chain A, interior..., B."""
        return np.vstack([vertices[self.start], self.points, vertices[self.end]])


@dataclass(frozen=True)
class Hole:
    """A closed walk: vertex indices (into the extended vertex array) in walking order, and
    the bridges it used as (bridge index, +1 forward / -1 backward)."""

    polygon: tuple[int, ...]
    bridges: tuple[tuple[int, int], ...] = ()
    parent: int = -1  # for holes made by splitting: the hole they came from

    @property
    def is_disk(self) -> bool:
        ids = [b for b, _ in self.bridges]
        return len(ids) == len(set(ids))


def resample_chain(polyline: NDArray[np.float64], spacing: float) -> NDArray[np.float64]:
    """Interior points of a polyline resampled at about ``spacing`` by arc length.

    The end points are kept exactly (they are mesh vertices); returns only the interior.
    """
    p = np.asarray(polyline, dtype=np.float64)
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    total = float(seg.sum())
    if total <= 0 or spacing <= 0:
        return np.zeros((0, 3))
    n = max(1, int(round(total / spacing)))
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.linspace(0.0, total, n + 1)[1:-1]
    return np.stack([np.interp(t, s, p[:, k]) for k in range(3)], axis=1)


def _dense(polyline: NDArray[np.float64], spacing: float) -> NDArray[np.float64]:
    p = np.asarray(polyline, dtype=np.float64)
    inner = resample_chain(p, spacing)
    return np.vstack([p[:1], inner, p[-1:]])


class BoundaryEdges:
    """The edges of the boundary loops, to tell a bridge that runs along the boundary.

    A bridge leaves its loop and crosses a hole; apart from its ends it stays off every boundary
    edge. One whose middle half comes within a small fraction of its length of a boundary edge
    (ConflictRules.along, 2 %) lies on the boundary: after the copies of a pinched vertex are
    merged it doubles an input edge and closes a tetrahedron (featuretype cut by balls and a slab:
    a row of wall triangles that touch at their corners, joined by straight bridges along each
    other's bottom edges, distance 0). The fraction is small on purpose: a chord along a curved rim
    runs a little inside it (6-10 % of its length at featuretype's through-holes), and such a
    chord may be the bridge of a real tunnel (with 5 % one was refused and a handle lost).
    Edges at the bridge's own end vertices are left out; copies of a vertex are other vertices,
    so their edges are tested. (Testing the edges at its ends too refused a tunnel bridge of
    featuretype cut by balls from a vertex to a copy of its neighbour: it lies on their border
    edge, yet without it a handle was lost.)

    ``fragments``: the faces of each fragment normalisation set aside. The repair walks them back
    into the holes after the bridges, so no bridge may cross their edges either (torus cut into two
    islands and a three-face fragment between them: a bridge along the other diagonal of the
    fragment's quad was walked twice, and the darning closed a pillow), except a bridge between two
    vertices of one fragment: it joins what the fragment joins (featuretype cut by a slab, a
    two-face fragment across the gap between two islands, tests/test_repair_cad_cuts.py).
    """

    def __init__(self, vertices: NDArray[np.float64], loops: list[NDArray[np.int64]],
                 faces: NDArray[np.int64] | None = None,
                 fragments: list[NDArray[np.int64]] | None = None) -> None:
        # faces: the surface's faces, for ``is_edge``
        # the surface's edges as sorted keys lo * n + hi (a set of tuples cost 60 ms on the bunny)
        self._face_edges = np.zeros(0, dtype=np.int64)
        self._n = len(vertices)
        # and the edges inside the set-aside fragments (two faces of one fragment): a fragment hanging
        # at a hole is put back into it (algorithms.fragments), and a bare bridge along such an edge
        # gave it four faces (every third face of a sphere, loose triangles touching at corners). A
        # fragment's border edges stay open to bridges (annulus sweep cut 4:0: refusing them lost
        # the ring's handle in light mode)
        known = [edge_table(np.asarray(faces, dtype=np.int64)).edges] if faces is not None and len(faces) else []
        for x in fragments or ():
            t = edge_table(np.asarray(x, dtype=np.int64).reshape(-1, 3))
            known.append(t.edges[t.counts == 2])
        fe = np.vstack(known) if known else np.zeros((0, 2), dtype=np.int64)
        if len(fe):
            self._n = max(self._n, int(fe.max()) + 1)
            self._face_edges = np.unique(fe[:, 0] * self._n + fe[:, 1])
        e = [np.stack([lp, np.roll(lp, -1)], axis=1) for lp in loops if len(lp) >= 2]
        # the fragment each edge belongs to (-1: a loop edge), and each fragment's vertices
        group = [np.full(len(x), -1) for x in e]
        self._fragment_vertices = [set(np.unique(f).tolist()) for f in fragments or ()]
        for k, f in enumerate(fragments or ()):
            fe = edge_table(np.asarray(f, dtype=np.int64)).edges
            e.append(fe)
            group.append(np.full(len(fe), k))
        self.group = np.concatenate(group) if group else np.zeros(0, dtype=np.int64)
        self.edges = np.concatenate(e).astype(np.int64) if e else np.zeros((0, 2), dtype=np.int64)
        p = np.asarray(vertices, dtype=np.float64)
        self.a, self.b = p[self.edges[:, 0]], p[self.edges[:, 1]]
        half = np.linalg.norm(self.b - self.a, axis=1) / 2
        self.reach = float(half.max()) if len(half) else 0.0
        self.tree = cKDTree((self.a + self.b) / 2) if len(self.edges) else None

    def is_edge(self, b: Bridge) -> bool:
        """Whether ``b`` is a bare chord (no interior point) between the two ends of an edge of the
        surface: it would give that edge a third and a fourth face (a tunnel line between two loops
        that one input edge joins across a thin strip: featuretype random cut 3:1). A chord to a
        copy of an edge's end (a pinched vertex split by normalisation) is another edge, unless the
        copies are merged later: counting copies refused the tunnel bridge of the featuretype slab
        cut (tests/test_repair_cad_cuts.py), genus 9 -> 8; the darning's pinch merge guards that
        case (repair's bare split chords, ``_is_edge`` with origins)."""
        lo, hi = min(b.start, b.end), max(b.start, b.end)
        if len(b.points) or not len(self._face_edges) or hi >= self._n:  # a new vertex is on no face
            return False
        key = lo * self._n + hi
        i = int(np.searchsorted(self._face_edges, key))
        return i < len(self._face_edges) and int(self._face_edges[i]) == key

    def distance(self, p0: NDArray[np.float64], p1: NDArray[np.float64], skip: set[int],
                 radius: float, fragments_only: bool = False) -> NDArray[np.float64]:
        """(K,) each segment p0[k] -> p1[k]'s distance to the nearest boundary edge (fragment edge, if
        ``fragments_only``) not at a vertex of ``skip``, nor of a fragment that holds all of ``skip``
        (inf beyond ``radius``)."""
        out = np.full(len(p0), np.inf)
        if self.tree is None or not len(p0):
            return out
        half = np.linalg.norm(p1 - p0, axis=1) / 2
        near = self.tree.query_ball_point((p0 + p1) / 2, half + radius + self.reach)
        seg = np.repeat(np.arange(len(p0)), [len(x) for x in near])
        if not len(seg):
            return out
        e = np.concatenate([np.asarray(x, dtype=np.int64) for x in near])
        keep = ~np.isin(self.edges[e], list(skip)).any(axis=1)
        own = [k for k, vs in enumerate(self._fragment_vertices) if skip <= vs]
        if own:
            keep &= ~np.isin(self.group[e], own)
        if fragments_only:
            keep &= self.group[e] >= 0
        seg, e = seg[keep], e[keep]
        # every (segment, nearby edge) pair at once; the nearest per segment
        np.minimum.at(out, seg, segment_distance(p0[seg], p1[seg], self.a[e], self.b[e]))
        return out

    def runs_along(self, b: Bridge, vertices: NDArray[np.float64], frac: float) -> bool:
        """Whether the middle half of ``b`` (by arc length) passes within ``frac`` x its length of
        a boundary edge not at its ends (crossing one included), or any part of it of a fragment's
        edge (a fragment is surface: a bridge that crosses it near its end cuts a chain of
        fragments in two, annulus sweep cut 8:1)."""
        poly = b.polyline(vertices)
        seg = np.linalg.norm(np.diff(poly, axis=0), axis=1)
        total = float(seg.sum())
        if total <= 0 or frac <= 0:
            return False
        s = np.concatenate([[0.0], np.cumsum(seg)])
        inner = (s > 0.25 * total) & (s < 0.75 * total)
        t = np.concatenate([[0.25 * total], s[inner], [0.75 * total]])
        mid = np.stack([np.interp(t, s, poly[:, k]) for k in range(3)], axis=1)
        tol = frac * total
        if (self.distance(mid[:-1], mid[1:], {b.start, b.end}, tol) < tol).any():
            return True
        return bool(self._fragment_vertices and
                    (self.distance(poly[:-1], poly[1:], {b.start, b.end}, tol, fragments_only=True) < tol).any())


def segment_distance(p0: NDArray[np.float64], p1: NDArray[np.float64], q0: NDArray[np.float64],
                     q1: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distances between segments p0 -> p1 and q0 -> q1, row by row (broadcast): the closest
    points' parameters s, t in [0, 1] minimise |p0 + s d1 - q0 - t d2| (clamped to the square,
    as in Ericson, Real-Time Collision Detection, 5.1.9)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e = (d1 * d1).sum(-1), (d2 * d2).sum(-1)
    b, c, f = (d1 * d2).sum(-1), (d1 * r).sum(-1), (d2 * r).sum(-1)
    tiny = 1e-300
    denom = a * e - b * b
    s = np.where(denom > 1e-12 * np.maximum(a * e, tiny), np.clip((b * f - c * e) / np.maximum(denom, tiny), 0, 1), 0.0)
    s = np.where(a > tiny, s, 0.0)
    t = np.where(e > tiny, (b * s + f) / np.maximum(e, tiny), 0.0)
    # t outside [0, 1]: clamp it and recompute s for the clamped t
    t = np.clip(t, 0.0, 1.0)
    s = np.where(a > tiny, np.clip((t * b - c) / np.maximum(a, tiny), 0.0, 1.0), 0.0)
    return np.linalg.norm(p0 + s[..., None] * d1 - q0 - t[..., None] * d2, axis=-1)


@dataclass(frozen=True)
class ConflictRules:
    """Thresholds of the conflict resolution (lengths in model units)."""

    clearance: float  # two bridges may not come closer than this (away from shared ends)
    neighbourhood: float  # two bridges between the same loops with both ends this close duplicate
    endpoint_gap: int = 2  # kept bridges' endpoints must be at least this many loop steps apart
    along: float = 0.02  # a bridge whose middle half passes closer than this x its length to a boundary edge


@dataclass
class GraphState:
    """Bridges kept so far and what is needed to test a new one against them."""

    vertices: NDArray[np.float64]
    loop_of: dict[int, tuple[int, int]]  # vertex -> (loop index, position in loop)
    loop_sizes: list[int]
    rules: ConflictRules
    kept: list[Bridge] = field(default_factory=list)
    boundary: BoundaryEdges | None = None  # the loops' edges no bridge may run along (None: not tested)
    reserved: set[int] = field(default_factory=set)  # vertices no bridge may end at (a fragment hangs there)
    _samples: list[NDArray[np.float64]] = field(default_factory=list)
    _tree: cKDTree | None = None  # over the kept bridges' samples, built when first needed after an add

    def conflict(self, b: Bridge, *, neighbourhood: float | None = None, near_ends: bool = True) -> str | None:
        """Why ``b`` conflicts with the kept bridges, or None. ``neighbourhood``: the duplicate
        distance for this bridge (default the rules'). ``near_ends`` False: the clearance is not
        tested within a clearance of an end of the bridge that lies at least a quarter of its loop
        from every kept bridge's end on that loop (two bridges to opposite sides of a small loop,
        a through-hole's rim, come closer than a clearance near it by necessity)."""
        near = self.rules.neighbourhood if neighbourhood is None else neighbourhood
        if b.start == b.end:
            return "starts and ends at the same vertex"
        if b.start in self.reserved or b.end in self.reserved:
            return "ends where a set-aside fragment hangs"
        la, ia = self.loop_of[b.start]
        lb, ib = self.loop_of[b.end]
        for k in self.kept:
            for v in (b.start, b.end):
                for w in (k.start, k.end):
                    lv, iv = self.loop_of[v]
                    lw, iw = self.loop_of[w]
                    if lv == lw:
                        d = abs(iv - iw)
                        d = min(d, self.loop_sizes[lv] - d)
                        if d < self.rules.endpoint_gap:
                            return f"shares an endpoint neighbourhood with bridge {k.start}-{k.end}"
            ka, kb = self.loop_of[k.start][0], self.loop_of[k.end][0]
            if {ka, kb} == {la, lb} and (self.end_distances(b, k) < near).all():
                return f"duplicates bridge {k.start}-{k.end} in the same neighbourhood"
        if self.boundary is not None and self.boundary.is_edge(b):
            return "is an edge of the surface already"
        if self.boundary is not None and self.boundary.runs_along(b, self.vertices, self.rules.along):
            return "runs along the boundary (its middle passes over a boundary edge)"
        if self.kept:
            pts = _dense(b.polyline(self.vertices), self.rules.clearance / 2)
            inner = pts[1:-1] if len(pts) > 2 else pts[:0]
            if not near_ends and len(inner):
                for v, end in ((b.start, pts[0]), (b.end, pts[-1])):
                    if self._apart_on_loop(v):
                        inner = inner[np.linalg.norm(inner - end, axis=1) >= self.rules.clearance]
            if len(inner):
                if self._tree is None:
                    self._tree = cKDTree(np.vstack(self._samples))
                d, _ = self._tree.query(inner, k=1)
                if (d < self.rules.clearance).any():
                    return "crosses or runs too close to a kept bridge"
        return None

    def end_distances(self, b: Bridge, k: Bridge) -> NDArray[np.float64]:
        """(2,) the distances between the ends of two bridges that join the same two loops: b's start
        to k's end on the same loop, and b's end to k's other end."""
        pa, pb = self.vertices[b.start], self.vertices[b.end]
        qa, qb = self.vertices[k.start], self.vertices[k.end]
        if self.loop_of[k.start][0] != self.loop_of[b.start][0]:
            qa, qb = qb, qa
        return np.array([np.linalg.norm(pa - qa), np.linalg.norm(pb - qb)])

    def _apart_on_loop(self, v: int) -> bool:
        """Whether every kept bridge's end on v's loop is at least a quarter of the loop from v."""
        lv, iv = self.loop_of[v]
        n = self.loop_sizes[lv]
        for k in self.kept:
            for w in (k.start, k.end):
                lw, iw = self.loop_of[w]
                if lw == lv and min(abs(iv - iw), n - abs(iv - iw)) < n / 4:
                    return False
        return True

    def add(self, b: Bridge) -> None:
        pts = _dense(b.polyline(self.vertices), self.rules.clearance / 2)
        self.kept.append(b)
        self._samples.append(pts[1:-1] if len(pts) > 2 else pts)
        self._tree = None


def walk_holes(loops: list[NDArray[np.int64]], bridges: list[Bridge],
               chains: list[NDArray[np.int64]]) -> list[Hole]:
    """Holes bounded by the loops and the bridges, by the walking rule (spec §6 step 1).

    loops: boundary loops (vertex indices, positive direction). bridges: with at most one
    bridge per vertex. chains: for each bridge, the vertex indices of its interior points in the
    extended vertex array, in order from start to end.
    Loops that no bridge touches come out unchanged as holes of their own.
    """
    nxt: dict[int, int] = {}
    for lp in loops:
        lp = [int(x) for x in lp]
        for a, b in zip(lp, lp[1:] + lp[:1]):
            nxt[a] = b
    at: dict[int, tuple[int, int]] = {}
    for k, br in enumerate(bridges):
        if br.start in at or br.end in at:
            raise ValueError(f"two bridges meet at vertex {br.start if br.start in at else br.end}")
        at[br.start] = (k, +1)
        at[br.end] = (k, -1)
    used: set[int] = set()  # boundary darts by start vertex
    holes: list[Hole] = []
    for lp in loops:
        for v0 in (int(x) for x in lp):
            if v0 in used:
                continue
            poly: list[int] = []
            used_bridges: list[tuple[int, int]] = []
            v = v0
            for _ in range(len(nxt) + 2 * sum(len(c) + 1 for c in chains) + 2):
                # traverse the boundary dart v -> nxt[v]
                used.add(v)
                poly.append(v)
                u = nxt[v]
                if u in at:
                    # arrived at a bridge vertex along the boundary: take the bridge
                    k, sign = at[u]
                    poly.append(u)
                    chain = chains[k] if sign > 0 else chains[k][::-1]
                    poly.extend(int(c) for c in chain)
                    used_bridges.append((k, sign))
                    w = bridges[k].end if sign > 0 else bridges[k].start
                    # on arriving, continue along the arrival loop: the dart w -> nxt[w]
                    v = w
                else:
                    v = u
                if v == v0 or v in used:
                    break
            holes.append(Hole(tuple(poly), tuple(used_bridges)))
    return holes


def split_polygon(polygon: tuple[int, ...], i: int, j: int,
                  chain: NDArray[np.int64]) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """Split a hole polygon by a chain from polygon[i] to polygon[j] (interior vertices).

    Each half walks the chain once, in opposite directions, so the two patches share it.
    """
    n = len(polygon)
    if i == j:
        raise ValueError("a split chain must join two different polygon vertices")
    seq1 = [polygon[(i + k) % n] for k in range(((j - i) % n) + 1)]  # p_i .. p_j
    seq2 = [polygon[(j + k) % n] for k in range(((i - j) % n) + 1)]  # p_j .. p_i
    c = [int(x) for x in chain]
    return tuple(seq1 + c[::-1]), tuple(seq2 + c)


class TopologyGuard:
    """What a new bridge does to the topology of the surface being built.

    Every hole is darned as a disk, so each bridge either
    - connects two components (its ends on surfaces not yet joined): the genus is unchanged;
    - splits one hole in two (both ends on the same walk): the genus is unchanged;
    - joins two different holes of one component: that adds a handle (genus + 1).
    The third kind is a tunnel, which only the tunnel rule (§6 step 2) may decide.

    A loop vertex v belongs to the walk that holds its boundary dart v -> next(v) (the walking rule
    of :func:`walk_holes`). Adding a bridge A-B changes only the walks through A and B: they are
    walked again from the darts at A and at B (two walks after a split, one after a merge), so a
    kept bridge costs the length of the walks it touches, not a walk of every hole.
    """

    def __init__(self, loops: list[NDArray[np.int64]], loop_island: list[int]) -> None:
        self.loops = loops
        self.parent = {i: i for i in set(loop_island)}
        self.island_of = {int(v): isl for lp, isl in zip(loops, loop_island) for v in lp}
        self._next: dict[int, int] = {}
        self.walk_of: dict[int, int] = {}
        for k, lp in enumerate(loops):
            lp = [int(x) for x in lp]
            for a, b in zip(lp, lp[1:] + lp[:1]):
                self._next[a] = b
                self.walk_of[a] = k
        self._other_end: dict[int, int] = {}
        self._walks = len(loops)

    def find(self, i: int) -> int:
        while self.parent[i] != i:
            self.parent[i] = self.parent[self.parent[i]]
            i = self.parent[i]
        return i

    def _darts(self, v0: int) -> list[int]:
        """The loop vertices whose darts the walk through dart v0 -> next(v0) takes, in order."""
        out, v = [], v0
        for _ in range(len(self._next) + 1):
            out.append(v)
            u = self._next[v]
            v = self._other_end.get(u, u)  # at a bridge end: cross, continue on the arrival loop
            if v == v0:
                break
        return out

    def add(self, b: Bridge) -> None:
        """Record a kept bridge: union its islands, walk again the (one or two) walks it touches."""
        self._other_end[b.start] = b.end
        self._other_end[b.end] = b.start
        ia, ib = self.island_of.get(b.start), self.island_of.get(b.end)
        if ia is not None and ib is not None:
            self.parent[self.find(ia)] = self.find(ib)
        for v0 in (b.start, b.end):
            walk = self._darts(v0)
            if v0 == b.end and b.start in walk:
                break  # one walk through both ends: labelled already
            self._walks += 1
            for v in walk:
                self.walk_of[v] = self._walks

    def effect(self, a: int, b: int) -> str:
        """"connect", "split" or "handle" for a bridge from loop vertex a to loop vertex b."""
        if self.find(self.island_of[a]) != self.find(self.island_of[b]):
            return "connect"
        return "split" if self.walk_of.get(a) == self.walk_of.get(b) else "handle"

    def components(self) -> dict[int, list[int]]:
        out: dict[int, list[int]] = {}
        for i in self.parent:
            out.setdefault(self.find(i), []).append(i)
        return out

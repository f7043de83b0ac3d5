"""Stage II: a constrained Delaunay triangulation in parameter space (spec/hybrid.md §3).

:class:`Triangulation` is a triangle-adjacency structure that the refinement (Stage III) updates
incrementally: every triangle stores its three vertices counter-clockwise in (u, v) and its three
neighbours (neighbour k is across the edge opposite vertex k; -1 on the border); border segments
are marked as constrained edges with their kind and their direction (kept region on the left).
Points are inserted by splitting a triangle or an edge and restoring the Delaunay property with
Lawson flips; the flip test is pluggable (the ordinary in-circle test in (u, v) for Stage II, the
3D cylinder test of Fig. 3 for Stage III). Constrained edges are never flipped.

Segments are recovered the way Ruppert's algorithm does: a segment missing from the Delaunay
triangulation of the border vertices has a vertex inside its diametral circle, so it is split at
its midpoint on the border curve (root finding on W) until every piece is an edge.

The per-triangle work is sequential by nature (each insertion changes the neighbourhood of the
next), so it is plain Python on floats; only the surface evaluations are vectorised.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from .border import CURVE, SIDE_UA, SIDE_UB, SIDE_VC, SIDE_VD, Border
from .incircle import incircle_2d, orient
from .model import HybridModel

INSIDE, BLOCKED = 0, 1
UV = tuple[float, float]


class Triangulation:
    """Incremental triangulation of the parameter rectangle with constrained border edges."""

    def __init__(self, model: HybridModel) -> None:
        self.model = model
        self.surface = model.surface
        self.uv: list[UV] = []
        self.p3: list[tuple[float, float, float]] = []
        self.tv: list[list[int]] = []
        self.tn: list[list[int]] = []
        self.alive: list[bool] = []
        self.vtri: list[int] = []
        self.seg: dict[tuple[int, int], tuple[int, int, int]] = {}  # (lo, hi) -> (kind, from, to)
        self.twin_of: dict[tuple[int, int, float, float], tuple[int, int]] = {}
        self.n_alive = 0
        self._seed = 12345
        self.flip_test: Callable[[int, int], bool] = self._flip_test_uv
        self.on_new_triangle: Callable[[list[int]], None] | None = None
        self.off_curve: dict[int, UV] = {}  # border vertices waiting to be moved onto F = 0
        self.failed_projections = 0
        a, b, c, d = self.surface.domain
        self.domain = (a, b, c, d)

    # ---- vertices and triangles -------------------------------------------------------------
    def add_vertex(self, uv: UV, p3: tuple[float, float, float] | None = None) -> int:
        if p3 is None:
            q = self.surface(np.array([uv[0]]), np.array([uv[1]]))[0]
            p3 = (float(q[0]), float(q[1]), float(q[2]))
        self.uv.append((float(uv[0]), float(uv[1])))
        self.p3.append(p3)
        self.vtri.append(-1)
        return len(self.uv) - 1

    def _new(self, a: int, b: int, c: int, na: int, nb: int, nc: int) -> int:
        self.tv.append([a, b, c])
        self.tn.append([na, nb, nc])
        self.alive.append(True)
        self.n_alive += 1
        return len(self.tv) - 1

    def _set(self, t: int, a: int, b: int, c: int, na: int, nb: int, nc: int) -> None:
        self.tv[t] = [a, b, c]
        self.tn[t] = [na, nb, nc]

    def _repoint(self, t: int, old: int, new: int) -> None:
        if t >= 0:
            row = self.tn[t]
            row[row.index(old)] = new

    def _rot(self, t: int, k: int) -> tuple[list[int], list[int]]:
        v, n = self.tv[t], self.tn[t]
        return [v[k], v[(k + 1) % 3], v[(k + 2) % 3]], [n[k], n[(k + 1) % 3], n[(k + 2) % 3]]

    def _touched(self, *ts: int) -> None:
        if self.on_new_triangle is not None:
            self.on_new_triangle(list(ts))

    def is_constrained(self, a: int, b: int) -> bool:
        return (a, b) in self.seg if a < b else (b, a) in self.seg

    def edge_constrained(self, t: int, k: int) -> bool:
        v = self.tv[t]
        return self.is_constrained(v[(k + 1) % 3], v[(k + 2) % 3])

    # ---- point location -----------------------------------------------------------------------
    def locate(self, p: UV, start: int, *, stop_at_segments: bool = False) -> tuple[int, int, int]:
        """Visibility walk from triangle `start` towards p.

        Returns (t, INSIDE, -1) for the triangle containing p, or (t, BLOCKED, k) when the walk has
        to leave t across edge k that is a border edge (or a constrained edge when stop_at_segments).
        """
        t = start
        uv, tv, tn = self.uv, self.tv, self.tn
        for _ in range(8 * len(tv) + 16):
            v = tv[t]
            moved = False
            self._seed = (self._seed * 1103515245 + 12345) & 0x7FFFFFFF
            r = self._seed % 3  # a random first edge: the walk cannot cycle in a non-Delaunay mesh
            for j in range(3):
                k = (r + j) % 3
                if orient(uv[v[(k + 1) % 3]], uv[v[(k + 2) % 3]], p) < 0:
                    n = tn[t][k]
                    if n < 0 or (stop_at_segments and self.is_constrained(v[(k + 1) % 3], v[(k + 2) % 3])):
                        return t, BLOCKED, k
                    t = n
                    moved = True
                    break
            if not moved:
                return t, INSIDE, -1
        raise RuntimeError("point location did not terminate (corrupt triangulation)")

    def any_alive(self) -> int:
        for t in range(len(self.tv) - 1, -1, -1):
            if self.alive[t]:
                return t
        raise RuntimeError("empty triangulation")

    # ---- insertion -------------------------------------------------------------------------------
    def insert(self, v: int, t: int, *, snap: bool = True) -> list[int]:
        """Insert vertex v (already added) into triangle t that contains it; returns new triangles.

        A point within 1e-9 (relative) of an edge is put exactly on it and splits the edge, so no
        flat triangle is ever created (snap=False: the point is never moved, only a point within
        1e-12 splits the edge; Stage II, whose border points must stay exactly where they are).
        """
        uv = self.uv
        p = uv[v]
        tv = self.tv[t]
        best, kbest = math.inf, -1
        for k in range(3):
            a, b = uv[tv[(k + 1) % 3]], uv[tv[(k + 2) % 3]]
            l2 = (b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2
            rel = orient(a, b, p) / l2 if l2 > 0 else 0.0
            if rel < best:
                best, kbest = rel, k
        if not snap:
            if abs(best) <= 1e-12:
                return self.split_edge(t, kbest, v)
            return self.split_triangle(t, v)
        if best <= 1e-9:
            a, b = uv[tv[(kbest + 1) % 3]], uv[tv[(kbest + 2) % 3]]
            dx, dy = b[0] - a[0], b[1] - a[1]
            s = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)
            s = min(max(s, 1e-6), 1 - 1e-6)
            q = (a[0] + s * dx, a[1] + s * dy)
            if q != p:
                r = self.surface(np.array([q[0]]), np.array([q[1]]))[0]
                uv[v] = q
                self.p3[v] = (float(r[0]), float(r[1]), float(r[2]))
            return self.split_edge(t, kbest, v)
        return self.split_triangle(t, v)

    def split_triangle(self, t: int, v: int) -> list[int]:
        (a, b, c), (na, nb, nc) = self.tv[t], self.tn[t]
        t1 = self._new(a, v, c, -1, nb, -1)
        t2 = self._new(a, b, v, -1, -1, nc)
        self._set(t, v, b, c, na, t1, t2)
        self.tn[t1][0], self.tn[t1][2] = t, t2
        self.tn[t2][0], self.tn[t2][1] = t, t1
        self._repoint(nb, t, t1)
        self._repoint(nc, t, t2)
        self.vtri[v] = self.vtri[b] = self.vtri[c] = t
        self.vtri[a] = t1
        self._legalize(v, [(t, 0), (t1, 1), (t2, 2)])
        return self._fan(v)

    def split_edge(self, t: int, k: int, v: int) -> list[int]:
        """Split the edge opposite vertex k of t by vertex v (on or near that edge)."""
        (r, p, q), (t2, n_p, n_q) = self._rot(t, k)
        key = (p, q) if p < q else (q, p)
        segment = self.seg.pop(key, None)
        A = t
        B = self._new(r, v, q, -1, n_p, A)
        if t2 >= 0:
            j = self.tv[t2].index(p)  # t2 = (s, q, p) rotated so that s is first
            (s, _q, _p), (_t, m_q, m_p) = self._rot(t2, (j + 1) % 3)
            C = t2
            D = self._new(s, v, p, A, m_q, C)
            self._set(C, s, q, v, B, D, m_p)
            self._repoint(m_q, t2, D)
            self.vtri[s] = C
        else:
            C = D = -1
        self._set(A, r, p, v, D, B, n_q)
        self.tn[B][0] = C
        self._repoint(n_p, t, B)
        self.vtri[v] = self.vtri[r] = self.vtri[p] = A
        self.vtri[q] = B
        if segment is not None:
            kind, fa, fb = segment
            self._add_segment(fa, v, kind)
            self._add_segment(v, fb, kind)
        todo = [(A, 2), (B, 1)] + ([(C, 2), (D, 1)] if C >= 0 else [])
        self._legalize(v, todo)
        return self._fan(v)

    def _add_segment(self, a: int, b: int, kind: int) -> None:
        self.seg[(a, b) if a < b else (b, a)] = (kind, a, b)

    def _flip_test_uv(self, t2: int, v: int) -> bool:
        a, b, c = self.tv[t2]
        return incircle_2d(self.uv[a], self.uv[b], self.uv[c], self.uv[v])

    def _legalize(self, v: int, todo: list[tuple[int, int]]) -> None:
        """Lawson flips around the new vertex v: only edges opposite v are tested, so v's degree
        grows with every flip and the loop terminates."""
        uv = self.uv
        while todo:
            t, i = todo.pop()
            t2 = self.tn[t][i]
            if t2 < 0:
                continue
            tv = self.tv[t]
            p, q = tv[(i + 1) % 3], tv[(i + 2) % 3]
            if self.is_constrained(p, q):
                continue
            s = self.tv[t2][3 - self.tv[t2].index(p) - self.tv[t2].index(q)]
            # flip only a strictly convex quad, so the (u, v) triangulation stays valid
            d2 = (uv[v][0] - uv[s][0]) ** 2 + (uv[v][1] - uv[s][1]) ** 2
            if orient(uv[v], uv[p], uv[s]) <= 1e-9 * d2 or orient(uv[s], uv[q], uv[v]) <= 1e-9 * d2:
                continue
            if not self.flip_test(t2, v):
                continue
            T, T2 = self.flip(t, i)
            todo.append((T, 0))
            todo.append((T2, 2))

    def flip(self, t: int, k: int) -> tuple[int, int]:
        """Flip the edge opposite vertex k of t; returns (T, T2) = ((r, p, s), (s, q, r))."""
        (r, p, q), (t2, n_p, n_q) = self._rot(t, k)
        j = self.tv[t2].index(p)
        (s, _q, _p), (_t, m_q, m_p) = self._rot(t2, (j + 1) % 3)
        self._set(t, r, p, s, m_q, t2, n_q)
        self._set(t2, s, q, r, n_p, t, m_p)
        self._repoint(m_q, t2, t)
        self._repoint(n_p, t, t2)
        self.vtri[r] = self.vtri[p] = self.vtri[s] = t
        self.vtri[q] = t2
        return t, t2

    def snapshot(self) -> tuple:
        """The mutable state (vertices, triangles, neighbours), to undo a pass with restore()."""
        return (list(self.uv), list(self.p3), [list(t) for t in self.tv], [list(t) for t in self.tn],
                list(self.alive), list(self.vtri), self.n_alive)

    def restore(self, state: tuple) -> None:
        uv, p3, tv, tn, alive, vtri, n_alive = state
        self.uv, self.p3, self.tv, self.tn = list(uv), list(p3), [list(t) for t in tv], [list(t) for t in tn]
        self.alive, self.vtri, self.n_alive = list(alive), list(vtri), n_alive

    def collapse(self, v: int, w: int) -> list[int]:
        """Remove interior vertex v by moving it onto its neighbour w (half-edge collapse): the two
        triangles on edge (v, w) die, the rest of v's fan take w instead of v. The caller has checked
        that v is not on a border segment and that the new fan is counter-clockwise in (u, v) (then
        the star of v is star-shaped from w and the result is a valid triangulation). Returns the
        triangles that now hold w instead of v."""
        fan = self._fan(v)
        dead = [t for t in fan if w in self.tv[t]]
        if len(dead) != 2:
            raise ValueError(f"collapse: {v} and {w} are not interior neighbours")
        for t in dead:
            tv, tn = self.tv[t], self.tn[t]
            i, j = tv.index(v), tv.index(w)
            x = tv[3 - i - j]
            a, b = tn[j], tn[i]  # across (v, x): a fan triangle of v; across (w, x): outside the fan
            self._repoint(a, t, b)
            self._repoint(b, t, a)
            self.alive[t] = False
            self.n_alive -= 1
            self.vtri[x] = a
        kept = [t for t in fan if t not in dead]
        for t in kept:
            tv = self.tv[t]
            tv[tv.index(v)] = w
        self.vtri[w] = kept[0]
        self.vtri[v] = -1
        self._touched(*kept)
        return kept

    # ---- fans and edges ----------------------------------------------------------------------------
    def _fan(self, v: int) -> list[int]:
        """The triangles around vertex v (in order around it; open fans at the border)."""
        t0 = self.vtri[v]
        out = [t0]
        t = t0
        while True:  # one way round: across the edge (v, next)
            i = self.tv[t].index(v)
            t = self.tn[t][(i + 2) % 3]
            if t < 0 or t == t0:
                break
            out.append(t)
        if t < 0:
            t = t0
            while True:
                i = self.tv[t].index(v)
                t = self.tn[t][(i + 1) % 3]
                if t < 0:
                    break
                out.insert(0, t)
        self._touched(*out)
        return out

    def fan(self, v: int) -> list[int]:
        cb, self.on_new_triangle = self.on_new_triangle, None
        try:
            return self._fan(v)
        finally:
            self.on_new_triangle = cb

    def find_edge(self, a: int, b: int) -> tuple[int, int] | None:
        for t in self.fan(a):
            tv = self.tv[t]
            if b in tv:
                return t, 3 - tv.index(a) - tv.index(b)
        return None

    # ---- segments ------------------------------------------------------------------------------------
    def midpoint_on_border(self, a: int, b: int, kind: int) -> tuple[UV, bool]:
        """The midpoint of border segment (a, b) on its border curve: the sides of P are straight
        in (u, v); a curve segment's midpoint is moved onto W = 0 by root finding across it."""
        pa, pb = self.uv[a], self.uv[b]
        m = (0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]))
        if kind != CURVE:
            return m, True
        du, dv = pb[0] - pa[0], pb[1] - pa[1]
        n = np.array([[-dv, du]])
        reach = 0.5 * np.hypot(du, dv)
        q, ok = self.model.project(np.array([m]), n, reach)
        if not ok[0]:
            self.failed_projections += 1
            return m, False
        return (float(q[0, 0]), float(q[0, 1])), True

    def midpoints_on_border(self, ends: list[tuple[int, int]]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """midpoint_on_border for several curve segments (a, b) at once (one vectorised root finding)."""
        pa = np.array([self.uv[a] for a, _ in ends], dtype=np.float64).reshape(-1, 2)
        pb = np.array([self.uv[b] for _, b in ends], dtype=np.float64).reshape(-1, 2)
        m = 0.5 * (pa + pb)
        dd = pb - pa
        n = np.stack([-dd[:, 1], dd[:, 0]], axis=1)
        q, ok = self.model.project(m, n, 0.5 * np.hypot(dd[:, 0], dd[:, 1]))
        self.failed_projections += int((~ok).sum())
        return q, ok

    def twin_segment(self, a: int, b: int, kind: int) -> tuple[int, int] | None:
        """For a seam side of a periodic direction, the segment on the opposite side."""
        s = self.surface
        if kind in (SIDE_VC, SIDE_VD) and s.periodic_v:
            other, coord = (SIDE_VD if kind == SIDE_VC else SIDE_VC), 0
        elif kind in (SIDE_UA, SIDE_UB) and s.periodic_u:
            other, coord = (SIDE_UB if kind == SIDE_UA else SIDE_UA), 1
        else:
            return None
        lo, hi = sorted((self.uv[a][coord], self.uv[b][coord]))
        return self.twin_of.get((other, coord, lo, hi))

    def index_seams(self) -> None:
        self.twin_of = {}
        for kind, a, b in self.seg.values():
            if kind == CURVE:
                continue
            coord = 0 if kind in (SIDE_VC, SIDE_VD) else 1
            lo, hi = sorted((self.uv[a][coord], self.uv[b][coord]))
            self.twin_of[(kind, coord, lo, hi)] = (a, b)

    # ---- Stage II ------------------------------------------------------------------------------------
    def build(self, border: Border) -> None:
        """Delaunay triangulation of the border vertices, segments recovered, outside removed."""
        a, b, c, d = self.domain
        mu, mv = 0.5 * (b - a), 0.5 * (d - c)
        nan3 = (np.nan, np.nan, np.nan)
        s0 = self.add_vertex((a - mu, c - mv), nan3)
        s1 = self.add_vertex((b + mu, c - mv), nan3)
        s2 = self.add_vertex((b + mu, d + mv), nan3)
        s3 = self.add_vertex((a - mu, d + mv), nan3)
        self.n_super = 4
        t0 = self._new(s0, s1, s2, -1, 1, -1)
        self._new(s0, s2, s3, -1, -1, 0)
        self.vtri[s0] = self.vtri[s1] = self.vtri[s2] = 0
        self.vtri[s3] = 1
        P3 = self.surface(border.points[:, 0], border.points[:, 1])
        ids = []
        t = t0
        for p, q in zip(border.points.tolist(), P3.tolist()):  # sequential incremental insertion
            v = self.add_vertex((p[0], p[1]), (q[0], q[1], q[2]))
            t, st, _ = self.locate(self.uv[v], t)
            t = self.insert(v, t, snap=False)[0]
            ids.append(v)
        ids_a = np.array(ids, dtype=np.int64)
        todo = [(int(ids_a[s0_]), int(ids_a[s1_]), int(k)) for (s0_, s1_), k in zip(border.segments, border.kinds)]
        # segments as constraints (Ruppert's recovery: a missing segment is encroached; split it)
        for a_, b_, k in todo:
            self._add_segment(a_, b_, k)
        self.index_seams()
        queue = list(todo)
        guard = 0
        while queue:
            a_, b_, k = queue.pop()
            if ((a_, b_) if a_ < b_ else (b_, a_)) not in self.seg or self.find_edge(a_, b_) is not None:
                continue
            guard += 1
            if guard > 200000:
                raise RuntimeError("segment recovery did not converge")
            for x, y, kk in self.split_segment_free(a_, b_, k):
                queue.append((x, y, kk))
        self._remove_outside()

    def split_segment_free(self, a: int, b: int, kind: int) -> list[tuple[int, int, int]]:
        """Stage II split of a missing segment (and of its seam twin): the midpoint on the border
        is inserted as a free vertex; returns the two halves (of each) to recover."""
        out = []
        pairs = [(a, b)]
        tw = self.twin_segment(a, b, kind)
        if tw is not None:
            pairs.append(tw)
        for x, y in pairs:
            key = (x, y) if x < y else (y, x)
            kk, fx, fy = self.seg.pop(key)
            m, _ = self.midpoint_on_border(fx, fy, kk)
            v = self.add_vertex(m)
            t, st, _ = self.locate(m, self.vtri[fx])
            self.insert(v, t, snap=False)
            self._add_segment(fx, v, kk)
            self._add_segment(v, fy, kk)
            out += [(fx, v, kk), (v, fy, kk)]
        self.index_seams()
        return out

    def _remove_outside(self) -> None:
        """Keep the regions bounded by the border on the left of its directed segments."""
        label = [-1] * len(self.tv)
        inside_of: list[bool] = []
        for t0 in range(len(self.tv)):
            if not self.alive[t0] or label[t0] >= 0:
                continue
            lab = len(inside_of)
            vote = 0
            stack = [t0]
            label[t0] = lab
            while stack:  # flood fill, not crossing constrained edges
                t = stack.pop()
                tv = self.tv[t]
                if min(tv) < self.n_super:
                    vote -= 1000
                for k in range(3):
                    p, q = tv[(k + 1) % 3], tv[(k + 2) % 3]
                    key = (p, q) if p < q else (q, p)
                    sg = self.seg.get(key)
                    if sg is not None:
                        vote += 1 if (sg[1], sg[2]) == (p, q) else -1  # t on the left of from→to
                        continue
                    n = self.tn[t][k]
                    if n >= 0 and label[n] < 0:
                        label[n] = lab
                        stack.append(n)
            inside_of.append(vote > 0)
        for t in range(len(self.tv)):
            if self.alive[t] and not inside_of[label[t]]:
                self.alive[t] = False
                self.n_alive -= 1
        for t in range(len(self.tv)):
            if self.alive[t]:
                row = self.tn[t]
                for k in range(3):
                    if row[k] >= 0 and not self.alive[row[k]]:
                        row[k] = -1
                for v in self.tv[t]:
                    self.vtri[v] = t
            else:
                self.tn[t] = [-1, -1, -1]

    # ---- output -----------------------------------------------------------------------------------------
    def faces(self) -> NDArray[np.int64]:
        return np.array([tv for tv, al in zip(self.tv, self.alive) if al], dtype=np.int64).reshape(-1, 3)

    def arrays(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
        """(uv (V, 2), points (V, 3), faces (F, 3)) compacted to the used vertices."""
        f = self.faces()
        used = np.unique(f.ravel())
        remap = -np.ones(len(self.uv), dtype=np.int64)
        remap[used] = np.arange(len(used))
        uv = np.array(self.uv, dtype=np.float64)[used]
        p3 = np.array(self.p3, dtype=np.float64)[used]
        return uv, p3, remap[f]

    def border_vertices(self) -> NDArray[np.int64]:
        return np.unique(np.array([[s[1], s[2]] for s in self.seg.values()], dtype=np.int64).ravel())

    def interior_mask(self, faces: NDArray[np.int64], only: NDArray[np.bool_] | None = None) -> NDArray[np.bool_]:
        """(V,) the vertices of `faces` not on a border segment (the ones the finishing passes may move
        or remove), restricted to the mask `only` when given."""
        m = np.zeros(len(self.uv), dtype=bool)
        m[np.unique(faces)] = True
        m[self.border_vertices()] = False
        if only is not None:
            m &= only[:len(m)]
        return m

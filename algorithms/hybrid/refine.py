"""Stage III: Ruppert-style Delaunay refinement on the surface (spec/hybrid.md §4).

Both geometric tests are done on the surface: the flip test is the 3D cylinder in-circle test of
Fig. 3 (6), and the point inserted for a bad triangle is its surface circumcentre, the parameter
point E minimising |R(u, v) − E3| (7) (Gauss-Newton from the affine guess). A triangle is bad
when its smallest 3D angle is below the threshold, its longest 3D edge exceeds the size limit, or
an edge's chord / arc ratio is below the curvature limit. When the circumcentre lies behind a
border edge or encroaches one (inside its diametral ball in 3D), the border edge is split instead,
at its midpoint on the border curve (F = 0 by root finding), together with its seam twin.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .border import CURVE
from .cdt import BLOCKED, Triangulation
from .chordal import chord_arc_ratios, chordal_errors, gauss_newton_step
from .incircle import circumcentre_3d, circumcircle_2d, local_frame, min_angle_3d, orient, to_local

SEED_SPLITS = 0  # seeding: border edges encroached by a seed split up to this many times before it is skipped


@dataclass(frozen=True)
class RefineParams:
    """min_angle: degrees (the bad-triangle threshold); max_edge: longest 3D edge (None: no limit);
    chord_arc: refine while an edge's chord / arc ratio is below this (0 disables);
    max_triangles: stop refining beyond this count; border_chord_arc: (choice) the same curvature
    criterion for the border curve F = 0 (chord against the two chords through its midpoint on
    the curve), split while below; cylinder: factor on the sampled deviation l of
    the surface from a triangle's plane (the half-height of the in-circle cylinder, Fig. 3);
    max_deviation: (choice) the curvature criterion in absolute form, the chordal error: refine a
    triangle while the surface over its edge midpoints or its centroid lies farther than this from
    it (chordal.py: the distance to the surface near them), and split a border segment while the
    border curve's midpoint lies farther than this from the chord (None: off). For an arc of
    curvature κ a chord of length h deviates by κh²/8, so this sizes the mesh h ∝ 1/√κ and spreads
    the chordal error evenly (the chord / arc ratio, 1 − κ²h²/24, sizes it h ∝ 1/κ);
    border_deviation: the tolerance for the border curve alone (None: max_deviation; math.inf: the
    border curve is then refined only by encroachment and border_chord_arc)."""

    min_angle: float = 30.0
    max_edge: float | None = None
    chord_arc: float = 0.98
    max_triangles: int = 200_000
    cylinder: float = 1.5
    border_chord_arc: float = 0.99
    max_deviation: float | None = None
    border_deviation: float | None = None

    def __post_init__(self) -> None:
        if not 0 <= self.min_angle <= 34:
            raise ValueError(f"min_angle: must be in [0, 34] degrees (refinement does not terminate "
                             f"above about 34), got {self.min_angle}")
        if self.max_edge is not None and not self.max_edge > 0:
            raise ValueError(f"max_edge: must be positive, got {self.max_edge}")
        if not 0 <= self.chord_arc < 1:
            raise ValueError(f"chord_arc: must be in [0, 1), got {self.chord_arc}")
        if self.max_triangles < 1:
            raise ValueError(f"max_triangles: must be at least 1, got {self.max_triangles}")
        if not 0 <= self.border_chord_arc < 1:
            raise ValueError(f"border_chord_arc: must be in [0, 1), got {self.border_chord_arc}")
        if self.max_deviation is not None and not self.max_deviation > 0:
            raise ValueError(f"max_deviation: must be positive, got {self.max_deviation}")
        if self.border_deviation is not None and not self.border_deviation > 0:
            raise ValueError(f"border_deviation: must be positive, got {self.border_deviation}")
        if not self.cylinder >= 1:
            raise ValueError(f"cylinder: must be at least 1, got {self.cylinder}")


@dataclass(frozen=True)
class RefineStats:
    inserted: int
    segment_splits: int
    skipped_corner: int
    hit_limit: bool
    off_curve: int


class Refiner:
    """Runs Stage III on a Triangulation built by Stage II."""

    def __init__(self, tri: Triangulation, params: RefineParams, *, corners: set[int] | None = None) -> None:
        self.tri = tri
        self.p = params
        self.size = tri.surface.size
        self.corners = corners or set()
        self.heap: list[tuple[float, float, int, int, tuple[int, int, int]]] = []
        self.seg_queue: list[tuple[int, int]] = []
        self.counter = 0
        self.arc_cache: dict[tuple[int, int], float] = {}
        self.inserted = 0
        self.seeded = 0
        self.seg_splits = 0
        self.skipped = 0
        self.target_cache: dict[tuple[int, int], tuple[tuple[float, float], bool]] = {}
        self.border_cache: dict[tuple[int, int], float] = {}
        self.circle_cache: dict[tuple[int, int, int], tuple | None] = {}
        self.dev_cache: dict[tuple[int, int, int], float] = {}
        self.chordal_cache: dict[tuple[int, int, int], float] = {}
        self.border_dev_cache: dict[tuple[int, int], float] = {}
        self.fallbacks = 0
        self.pending: list[int] = []
        bd = params.border_deviation if params.border_deviation is not None else params.max_deviation
        self.border_tol = bd if bd is not None and math.isfinite(bd) else None
        a, b, c, d = tri.domain
        self.h = (1e-7 * (b - a), 1e-7 * (d - c))
        self.box = (a - (b - a), b + (b - a), c - (d - c), d + (d - c))
        self.lmin = 1e-9 * self.size

    # ---- quality -----------------------------------------------------------------------------------
    def chord_arc(self, a: int, b: int) -> float:
        key = (a, b) if a < b else (b, a)
        r = self.arc_cache.get(key)
        if r is None:
            self._arcs([key])
            r = self.arc_cache[key]
        return r

    def _arcs(self, keys: list[tuple[int, int]]) -> None:
        """chord / arc for edges: the arc is the polyline through the surface at 1/4, 1/2, 3/4 of
        the parameter segment (one vectorised surface call for all the edges)."""
        tri = self.tri
        uv = np.array([[tri.uv[a], tri.uv[b]] for a, b in keys])  # (K, 2, 2)
        ends = np.array([[tri.p3[a], tri.p3[b]] for a, b in keys])
        for k, r in zip(keys, chord_arc_ratios(tri.surface, uv, ends).tolist()):
            self.arc_cache[k] = r

    def _chordal(self, ts: list[int]) -> None:
        """The chordal error of triangles (max_deviation, chordal.py), all of them in two surface calls."""
        tri = self.tri
        keys = [tuple(tri.tv[t]) for t in ts]
        p3, uv = tri.p3, tri.uv
        T3 = np.array([[p3[a], p3[b], p3[c]] for a, b, c in keys])
        T2 = np.array([[uv[a], uv[b], uv[c]] for a, b, c in keys])
        for k, d in zip(keys, chordal_errors(tri.surface, T3, T2).tolist()):
            self.chordal_cache[k] = d

    def chordal(self, t: int) -> float:
        key = tuple(self.tri.tv[t])
        d = self.chordal_cache.get(key)
        if d is None:
            self._chordal([t])
            d = self.chordal_cache[key]
        return d

    def badness(self, t: int) -> tuple[float, float] | None:
        """None for a good triangle, else its priority (smaller first)."""
        tri = self.tri
        a, b, c = tri.tv[t]
        A, B, C = tri.p3[a], tri.p3[b], tri.p3[c]
        ang, k = min_angle_3d(A, B, C)
        lmax = math.sqrt(max(_d2(A, B), _d2(B, C), _d2(C, A)))
        if self.p.max_edge is not None and lmax > self.p.max_edge:
            return (0.0, -lmax)
        if self.p.chord_arc > 0:
            cache = self.arc_cache
            keys = [(x, y) if x < y else (y, x) for x, y in ((a, b), (b, c), (c, a))]
            missing = [k for k in keys if k not in cache]
            if missing:
                self._arcs(missing)
            worst = min(cache[k] for k in keys)
            if worst < self.p.chord_arc:
                return (0.0, -lmax)
        if self.p.max_deviation is not None and self.chordal(t) > self.p.max_deviation:
            return (0.0, -lmax)
        if ang < self.p.min_angle:
            if (a, b, c)[k] in self.corners:
                self.skipped += 1
                return None
            return (1.0, ang)
        return None

    def push_many(self, ts: list[int]) -> None:
        """Queue new triangles; their missing chord / arc ratios in one surface call, the missing border
        ratios of their curve edges in one root-finding call."""
        tri = self.tri
        cache = self.arc_cache
        missing = set()
        curve_missing = set()
        for t in ts:
            a, b, c = tri.tv[t]
            for x, y in ((a, b), (b, c), (c, a)):
                k = (x, y) if x < y else (y, x)
                if self.p.chord_arc > 0 and k not in cache:
                    missing.add(k)
                if (self.p.border_chord_arc > 0 or self.border_tol is not None) and k in tri.seg \
                        and k not in self.border_cache:
                    curve_missing.add(k)
        if missing:
            self._arcs(sorted(missing))
        if self.p.max_deviation is not None:
            todo = [t for t in ts if tri.alive[t] and tuple(tri.tv[t]) not in self.chordal_cache]
            if todo:
                self._chordal(todo)
        if curve_missing:
            self._border_ratios(sorted(curve_missing))
        for t in ts:
            self.push(t)

    def push(self, t: int) -> None:
        tri = self.tri
        if not tri.alive[t]:
            return
        tv = tri.tv[t]
        # encroached border edges of this triangle (by its own apex): queue them first (Ruppert)
        for k in range(3):
            p, q = tv[(k + 1) % 3], tv[(k + 2) % 3]
            if tri.is_constrained(p, q) and self.segment_bad(p, q, tv[k]):
                self.seg_queue.append((p, q))
        bad = self.badness(t)
        if bad is not None:
            self.counter += 1
            heapq.heappush(self.heap, (bad[0], bad[1], self.counter, t, (tv[0], tv[1], tv[2])))

    def segment_bad(self, p: int, q: int, apex: int) -> bool:
        P, Q, R = self.tri.p3[p], self.tri.p3[q], self.tri.p3[apex]
        if _dot_sub(P, R, Q, R) < 0:  # the apex is inside the diametral ball: encroached
            return True
        if self.p.max_edge is not None and _d2(P, Q) > self.p.max_edge ** 2:
            return True
        if self.p.chord_arc > 0 and self.chord_arc(p, q) < self.p.chord_arc:
            return True
        if self.border_tol is not None and self.border_deviation(p, q) > self.border_tol:
            return True
        return self.p.border_chord_arc > 0 and self.border_ratio(p, q) < self.p.border_chord_arc

    def border_ratio(self, p: int, q: int) -> float:
        """chord / arc of a curve segment, the arc through its midpoint on F = 0 (cached)."""
        key = (p, q) if p < q else (q, p)
        hit = self.border_cache.get(key)
        if hit is None:
            self._border_ratios([key])
            hit = self.border_cache[key]
        return hit

    def border_deviation(self, p: int, q: int) -> float:
        """The distance of a curve segment's midpoint on F = 0 from the middle of its chord (3D)."""
        key = (p, q) if p < q else (q, p)
        if key not in self.border_cache:
            self._border_ratios([key])
        return self.border_dev_cache.get(key, 0.0)

    def _border_ratios(self, keys: list[tuple[int, int]]) -> None:
        """border_ratio for several segments: their midpoints on F = 0 found together (one vectorised
        root finding, Triangulation.midpoints_on_border), kept as the split targets."""
        tri = self.tri
        curve = []
        for key in keys:
            sg = tri.seg.get(key)
            if sg is not None and sg[0] == CURVE:
                curve.append(key)
            else:
                self.border_cache[key] = 1.0
        if not curve:
            return
        ends = [(tri.seg[k][1], tri.seg[k][2]) for k in curve]
        targets, ok = tri.midpoints_on_border(ends)
        M = tri.surface(targets[:, 0], targets[:, 1])
        P = np.array([tri.p3[a] for a, _ in ends])
        Q = np.array([tri.p3[b] for _, b in ends])
        arc = np.linalg.norm(M - P, axis=1) + np.linalg.norm(Q - M, axis=1)
        chord = np.linalg.norm(Q - P, axis=1)
        ratio = np.where(ok & (arc > 0), chord / np.where(arc > 0, arc, 1.0), 1.0)
        dev = np.where(ok, np.linalg.norm(M - 0.5 * (P + Q), axis=1), 0.0)
        for k, tgt, good, r, e in zip(curve, targets.tolist(), ok.tolist(), ratio.tolist(), dev.tolist()):
            self.target_cache[k] = ((tgt[0], tgt[1]), good)
            self.border_cache[k] = r
            self.border_dev_cache[k] = e

    # ---- the 3D flip test (Fig. 3) ----------------------------------------------------------------------
    def deviation(self, t: int) -> float:
        """l: the largest distance along the normal between the triangle's plane and the surface over
        its circumscribed disk (where the points tested against it lie), sampled at the centroid, the
        circumcentre and six points at 0.95 of the circumradius, mapped to (u, v) by the affine map
        of the triangle; times the cylinder factor (choice)."""
        tri = self.tri
        a, b, c = tri.tv[t]
        key3 = (a, b, c)
        hit = self.dev_cache.get(key3)
        if hit is not None:
            return hit
        A, B, C = tri.p3[a], tri.p3[b], tri.p3[c]
        fr = local_frame(A, B, C)
        if fr is None:
            return self.lmin
        bx = to_local(fr, A, B)[0]
        cl = to_local(fr, A, C)
        ex, ey, r2 = circumcircle_2d(bx, cl[0], cl[1])
        r = 0.95 * math.sqrt(r2)
        th = np.linspace(0, 2 * np.pi, 6, endpoint=False)
        lx = np.r_[(bx + cl[0]) / 3, ex, ex + r * np.cos(th)]
        ly = np.r_[cl[1] / 3, ey, ey + r * np.sin(th)]
        lc = ly / cl[1]
        lb = (lx - lc * cl[0]) / bx
        la = 1.0 - lb - lc
        uvs = np.array([tri.uv[a], tri.uv[b], tri.uv[c]])
        s = la[:, None] * uvs[0] + lb[:, None] * uvs[1] + lc[:, None] * uvs[2]
        s[:, 0] = np.clip(s[:, 0], self.box[0], self.box[1])
        s[:, 1] = np.clip(s[:, 1], self.box[2], self.box[3])
        q = tri.surface(s[:, 0], s[:, 1])
        n = np.array(fr[2])
        dev = float(np.abs((q - np.array(A)) @ n).max())
        out = self.p.cylinder * dev + self.lmin
        self.dev_cache[key3] = out
        return out

    def circle(self, t: int) -> tuple | None:
        """(E3, r², A3, normal) of triangle t: its circumcircle in space (cached), the same circle
        as the local-frame construction of Fig. 3 (incircle.incircle_3d)."""
        tri = self.tri
        a, b, c = tri.tv[t]
        key = (a, b, c)
        hit = self.circle_cache.get(key)
        if hit is not None:
            return hit
        A, B, C = tri.p3[a], tri.p3[b], tri.p3[c]
        ax, ay, az = A[0] - C[0], A[1] - C[1], A[2] - C[2]
        bx, by, bz = B[0] - C[0], B[1] - C[1], B[2] - C[2]
        nx, ny, nz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        n2 = nx * nx + ny * ny + nz * nz
        a2, b2 = ax * ax + ay * ay + az * az, bx * bx + by * by + bz * bz
        if n2 <= 1e-30 * a2 * b2 or n2 == 0.0:
            self.circle_cache[key] = None
            return None
        # E3 − C3 = ((|a|² b − |b|² a) × (a × b)) / (2 |a × b|²)
        wx, wy, wz = a2 * bx - b2 * ax, a2 * by - b2 * ay, a2 * bz - b2 * az
        ex = (wy * nz - wz * ny) / (2 * n2)
        ey = (wz * nx - wx * nz) / (2 * n2)
        ez = (wx * ny - wy * nx) / (2 * n2)
        nl = math.sqrt(n2)
        out = ((C[0] + ex, C[1] + ey, C[2] + ez), ex * ex + ey * ey + ez * ez, A, (nx / nl, ny / nl, nz / nl))
        self.circle_cache[key] = out
        return out

    def in_cylinder(self, t: int, P: tuple, *, height: bool = True) -> bool:
        """Fig. 3 with the cached circle: P projected on the triangle's plane inside the circumcircle,
        and (height) |z′| ≤ l."""
        cc = self.circle(t)
        if cc is None:
            return False
        E, r2, A, n = cc
        z = (P[0] - A[0]) * n[0] + (P[1] - A[1]) * n[1] + (P[2] - A[2]) * n[2]
        dx, dy, dz = P[0] - E[0] - z * n[0], P[1] - E[1] - z * n[1], P[2] - E[2] - z * n[2]
        if dx * dx + dy * dy + dz * dz >= r2 * (1.0 - 1e-12):
            return False
        if not height:
            return True
        # l: the sampled deviation of the surface (times the cylinder factor), but (choice) never
        # less than half the circumradius: a point that far off the plane is on another sheet;
        # nearer ones are the surface curving (a too thin cylinder stops the flips that remove
        # bad triangles, and the refinement then cascades)
        z = abs(z)
        return z * z <= 0.25 * r2 or z <= self.deviation(t)

    def flip_test(self, t2: int, v: int) -> bool:
        return self.in_cylinder(t2, self.tri.p3[v])

    # ---- eq. (7): the surface circumcentre --------------------------------------------------------------
    def surface_point(self, t: int, E3: tuple[float, float, float]) -> tuple[float, float, tuple] | None:
        tri = self.tri
        a, b, c = tri.tv[t]
        A, B, C = tri.p3[a], tri.p3[b], tri.p3[c]
        fr = local_frame(A, B, C)
        if fr is None:
            return None
        bx = to_local(fr, A, B)[0]
        cl = to_local(fr, A, C)
        el = to_local(fr, A, E3)
        # barycentric coordinates of E3′ in A′B′C′, carried over to (u, v): the starting point
        lc = el[1] / cl[1]
        lb = (el[0] - lc * cl[0]) / bx
        la = 1.0 - lb - lc
        ua, ub, uc = tri.uv[a], tri.uv[b], tri.uv[c]
        u = la * ua[0] + lb * ub[0] + lc * uc[0]
        v = la * ua[1] + lb * ub[1] + lc * uc[1]
        hu, hv = self.h
        box = self.box
        tol_u, tol_v = 1e-9 * (box[1] - box[0]), 1e-9 * (box[3] - box[2])
        ex, ey, ez = E3
        R = None
        for _ in range(4):  # Gauss-Newton on |R(u, v) − E3|²  (7); one surface call per step
            u = min(max(u, box[0]), box[1])
            v = min(max(v, box[2]), box[3])
            q = tri.surface(np.array([u, u + hu, u]), np.array([v, v, v + hv])).tolist()
            R = q[0]
            ju = ((q[1][0] - R[0]) / hu, (q[1][1] - R[1]) / hu, (q[1][2] - R[2]) / hu)
            jv = ((q[2][0] - R[0]) / hv, (q[2][1] - R[1]) / hv, (q[2][2] - R[2]) / hv)
            r0, r1, r2 = R[0] - ex, R[1] - ey, R[2] - ez
            a11 = ju[0] * ju[0] + ju[1] * ju[1] + ju[2] * ju[2]
            a12 = ju[0] * jv[0] + ju[1] * jv[1] + ju[2] * jv[2]
            a22 = jv[0] * jv[0] + jv[1] * jv[1] + jv[2] * jv[2]
            det = a11 * a22 - a12 * a12
            if det <= 0:
                break
            g1 = ju[0] * r0 + ju[1] * r1 + ju[2] * r2
            g2 = jv[0] * r0 + jv[1] * r1 + jv[2] * r2
            du = -(a22 * g1 - a12 * g2) / det
            dv = -(a11 * g2 - a12 * g1) / det
            if abs(du) < tol_u and abs(dv) < tol_v:  # converged: R is the surface point at (u, v)
                return u, v, (R[0], R[1], R[2])
            u += du
            v += dv
        u = min(max(u, box[0]), box[1])
        v = min(max(v, box[2]), box[3])
        q = tri.surface(np.array([u]), np.array([v]))[0]
        return u, v, (float(q[0]), float(q[1]), float(q[2]))

    # ---- segment splitting --------------------------------------------------------------------------------
    def split_segment(self, a: int, b: int) -> bool:
        tri = self.tri
        key = (a, b) if a < b else (b, a)
        sg = tri.seg.get(key)
        if sg is None:
            return False
        pairs = [(a, b)]
        tw = tri.twin_segment(a, b, sg[0])
        if tw is not None:
            pairs.append(tw)
        new = []
        cb, tri.on_new_triangle = tri.on_new_triangle, None  # queue the fans once on the curve
        try:
            for x, y in pairs:
                found = tri.find_edge(x, y)
                if found is None:
                    continue
                key2 = (x, y) if x < y else (y, x)
                kind, fx, fy = tri.seg[key2]
                hit = self.target_cache.pop(key2, None) if kind == CURVE else None
                target = hit[0] if hit is not None else tri.midpoint_on_border(fx, fy, kind)[0]
                ux, uy = tri.uv[fx], tri.uv[fy]
                mid = (0.5 * (ux[0] + uy[0]), 0.5 * (ux[1] + uy[1]))
                t, k = found
                v = tri.add_vertex(mid)
                tri.split_edge(t, k, v)
                if kind == CURVE:
                    self.move_onto_curve(v, target, queue=False)
                new.append(v)
                self.seg_splits += 1
        finally:
            tri.on_new_triangle = cb
        if sg[0] != CURVE:  # the seam index holds the sides of P only
            tri.index_seams()
        if new:
            self.pending.extend(t for v in new for t in tri.fan(v))
        return True

    def move_onto_curve(self, v: int, target: tuple[float, float], *, queue: bool = True) -> bool:
        """Move a border vertex from its chord midpoint onto F = 0 if its fan stays valid in (u, v)."""
        tri = self.tri
        fan = tri.fan(v)
        for t in fan:
            tv = tri.tv[t]
            i = tv.index(v)
            if orient(target, tri.uv[tv[(i + 1) % 3]], tri.uv[tv[(i + 2) % 3]]) <= 0:
                tri.off_curve[v] = target
                return False
        q = tri.surface(np.array([target[0]]), np.array([target[1]]))[0]
        tri.uv[v] = target
        tri.p3[v] = (float(q[0]), float(q[1]), float(q[2]))
        tri.off_curve.pop(v, None)
        for t in fan:  # cached edge ratios and deviations around v are stale now
            tv = tri.tv[t]
            self.dev_cache.pop((tv[0], tv[1], tv[2]), None)
            self.circle_cache.pop((tv[0], tv[1], tv[2]), None)
            self.chordal_cache.pop((tv[0], tv[1], tv[2]), None)
            for w in tv:
                if w != v:
                    k2 = (v, w) if v < w else (w, v)
                    self.arc_cache.pop(k2, None)
                    self.border_cache.pop(k2, None)
                    self.border_dev_cache.pop(k2, None)
                    self.target_cache.pop(k2, None)
        tri._legalize(v, [(t, tri.tv[t].index(v)) for t in fan])
        if queue:
            self.pending.extend(tri.fan(v))
        return True

    # ---- the main loop ----------------------------------------------------------------------------------------
    def run(self) -> RefineStats:
        """Refinement in rounds (the order of insertions is free in Ruppert's algorithm): the triangles
        made since the last round are assessed together (chord / arc, chordal error and border ratios:
        a few vectorised surface calls), the encroached or bad border segments are split, then every bad
        triangle known at the start of the round is refined in priority order (skipping those an earlier
        insertion removed), its surface circumcentre found with the others in one vectorised
        Gauss-Newton (7). The insertions themselves are sequential: each changes what the next one sees."""
        tri = self.tri
        tri.flip_test = self.flip_test
        self.pending = [t for t in range(len(tri.tv)) if tri.alive[t]]
        tri.on_new_triangle = self._collect
        hit = False
        while True:
            if tri.n_alive >= self.p.max_triangles:
                hit = True
                break
            if self.pending:
                ts = list(dict.fromkeys(self.pending))
                self.pending = []
                self.push_many([t for t in ts if tri.alive[t]])
            if self.seg_queue:
                segs, self.seg_queue = self.seg_queue, []
                for p, q in reversed(segs):
                    if tri.n_alive >= self.p.max_triangles:
                        break
                    found = tri.find_edge(p, q) if tri.is_constrained(p, q) else None
                    if found is not None and self.segment_bad(p, q, tri.tv[found[0]][found[1]]):
                        self.split_segment(p, q)
                continue
            if not self.heap:
                if self.pending or self._retry_off_curve():
                    continue
                break
            items = [heapq.heappop(self.heap) for _ in range(len(self.heap))]
            todo = [(t, verts) for *_, t, verts in items if tri.alive[t] and tuple(tri.tv[t]) == verts]
            sps = self._surface_points([t for t, _ in todo])
            for (t, verts), sp in zip(todo, sps):
                if tri.n_alive >= self.p.max_triangles:
                    break
                if not tri.alive[t] or tuple(tri.tv[t]) != verts or self.badness(t) is None:
                    continue
                self.refine_triangle(t, sp)
        tri.on_new_triangle = None
        return RefineStats(self.inserted, self.seg_splits, self.skipped, hit, len(tri.off_curve))

    def split_long_segments(self, limit: float, *, rounds: int = 30) -> int:
        """Split border segments longer than limit in space at their midpoints on the border (the same
        split as for encroachment), until none is (before seeding: a long segment's diametral ball
        would keep the seeds far from it). Returns the number of splits."""
        tri = self.tri
        done = 0
        for _ in range(rounds):
            long = [(a, b) for _k, a, b in list(tri.seg.values()) if _d2(tri.p3[a], tri.p3[b]) > limit * limit]
            if not long:
                break
            for a, b in long:
                if tri.is_constrained(a, b) and self.split_segment(a, b):
                    done += 1
        return done

    def seed(self, points: NDArray[np.float64]) -> int:
        """Insert interior points before run() (seeding.py): Delaunay insertion with the 3D flip test,
        each point located from the triangle of its nearest vertex; a point behind a border edge, on a
        vertex or encroaching a border edge is skipped. Returns the number inserted."""
        from scipy.spatial import cKDTree

        tri = self.tri
        if not len(points):
            return 0
        tri.flip_test = self.flip_test
        P3 = tri.surface(points[:, 0], points[:, 1])
        used = [v for v in range(len(tri.uv)) if tri.vtri[v] >= 0 and tri.alive[tri.vtri[v]]]
        near = cKDTree(np.array([tri.uv[v] for v in used]))
        _, idx = near.query(points)
        done = 0
        last = -1
        for (u, v), X, k in zip(points.tolist(), P3.tolist(), idx.tolist()):
            X = (X[0], X[1], X[2])
            for _attempt in range(SEED_SPLITS + 1):
                start = last if last >= 0 and tri.alive[last] else tri.vtri[used[k]]
                if start < 0 or not tri.alive[start]:
                    start = tri.any_alive()
                t, status, _k = tri.locate((u, v), start, stop_at_segments=True)
                if status == BLOCKED and start != tri.vtri[used[k]] and tri.alive[tri.vtri[used[k]]]:
                    t, status, _k = tri.locate((u, v), tri.vtri[used[k]], stop_at_segments=True)
                if status == BLOCKED or any(_d2(tri.p3[w], X) <= (1e-9 * self.size) ** 2 for w in tri.tv[t]):
                    break
                enc = self.encroached_by(t, X)
                if enc:  # Ruppert's rule: the border edges the point encroaches are split first
                    if _attempt < SEED_SPLITS:
                        for p, q in enc:
                            self.split_segment(p, q)
                    continue
                w = tri.add_vertex((u, v), X)
                tri.insert(w, t)
                last = tri.vtri[w]
                done += 1
                break
        self.seeded += done
        return done

    def _collect(self, ts: list[int]) -> None:
        self.pending.extend(ts)

    def _surface_points(self, ts: list[int]) -> list[tuple[float, float, tuple] | None]:
        """surface_point for many triangles at once: the 3D circumcentres E3, the affine guesses in (u, v),
        then Gauss-Newton on |R(u, v) − E3|² (7) vectorised (one surface call per step for all)."""
        tri = self.tri
        out: list[tuple[float, float, tuple] | None] = [None] * len(ts)
        rows, E, G = [], [], []
        for i, t in enumerate(ts):
            a, b, c = tri.tv[t]
            A, B, C = tri.p3[a], tri.p3[b], tri.p3[c]
            fr = local_frame(A, B, C)
            if fr is None:
                continue
            bx = to_local(fr, A, B)[0]
            cl = to_local(fr, A, C)
            ex, ey, _ = circumcircle_2d(bx, cl[0], cl[1])
            x, y, _z = fr
            E3 = (A[0] + x[0] * ex + y[0] * ey, A[1] + x[1] * ex + y[1] * ey, A[2] + x[2] * ex + y[2] * ey)
            lc = ey / cl[1]  # barycentric coordinates of E3′ in A′B′C′, carried over to (u, v)
            lb = (ex - lc * cl[0]) / bx
            la = 1.0 - lb - lc
            ua, ub, uc = tri.uv[a], tri.uv[b], tri.uv[c]
            rows.append(i)
            E.append(E3)
            G.append((la * ua[0] + lb * ub[0] + lc * uc[0], la * ua[1] + lb * ub[1] + lc * uc[1]))
        if not rows:
            return out
        E3s = np.array(E)
        uv = np.array(G)
        box = self.box
        lo, hi = np.array([box[0], box[2]]), np.array([box[1], box[3]])
        hu, hv = self.h
        k = len(uv)
        for _ in range(4):
            uv = np.clip(uv, lo, hi)
            q = tri.surface(np.r_[uv[:, 0], uv[:, 0] + hu, uv[:, 0]], np.r_[uv[:, 1], uv[:, 1], uv[:, 1] + hv])
            R = q[:k]
            ju, jv = (q[k:2 * k] - R) / hu, (q[2 * k:] - R) / hv
            step = np.stack(gauss_newton_step(ju, jv, E3s - R), axis=1)  # eq. (7), all at once
            uv = uv + step
            if (np.abs(step) <= 1e-9 * (hi - lo)).all():
                break
        uv = np.clip(uv, lo, hi)
        P = tri.surface(uv[:, 0], uv[:, 1])
        for i, (u, v), (x, y, z) in zip(rows, uv.tolist(), P.tolist()):
            out[i] = (u, v, (x, y, z))
        return out

    def _retry_off_curve(self) -> bool:
        """Once the queues are empty: move border vertices still on their chords onto F = 0."""
        moved = False
        for v, target in list(self.tri.off_curve.items()):
            if v in self.tri.off_curve and self.move_onto_curve(v, target):
                moved = True
        return moved

    def refine_triangle(self, t: int, sp: tuple[float, float, tuple] | None = None) -> None:
        tri = self.tri
        a, b, c = tri.tv[t]
        if sp is None:
            E3 = circumcentre_3d(tri.p3[a], tri.p3[b], tri.p3[c])
            sp = self.surface_point(t, E3) if E3 is not None else None
        if sp is not None:
            u, v, P3 = sp
            t2, status, k = tri.locate((u, v), t, stop_at_segments=True)
            if status == BLOCKED:
                # the circumcentre lies behind a border edge: split that edge if it encroaches it
                # (Ruppert); far from the border on a coarse, strongly curved mesh it may not
                tv = tri.tv[t2]
                p, q = tv[(k + 1) % 3], tv[(k + 2) % 3]
                if _dot_sub(tri.p3[p], P3, tri.p3[q], P3) < 0:
                    self.split_segment(p, q)
                    self._requeue(t)
                    return
            else:
                if self._insert_or_split(t, t2, (u, v), P3):
                    return
        # fallback: the parameter-space centroid of t (inside t by construction)
        ua, ub, uc = tri.uv[a], tri.uv[b], tri.uv[c]
        g = ((ua[0] + ub[0] + uc[0]) / 3.0, (ua[1] + ub[1] + uc[1]) / 3.0)
        q = tri.surface(np.array([g[0]]), np.array([g[1]]))[0]
        self._insert_or_split(t, t, g, (float(q[0]), float(q[1]), float(q[2])))
        self.fallbacks += 1

    def _insert_or_split(self, t: int, t2: int, uv: tuple[float, float], P3: tuple) -> bool:
        """Insert the point (in triangle t2) unless it encroaches border edges: split those."""
        tri = self.tri
        for w in tri.tv[t2]:  # the point is a vertex already (its triangle survived an earlier insertion)
            if _d2(tri.p3[w], P3) <= (1e-9 * self.size) ** 2 or tri.uv[w] == uv:
                return False
        enc = self.encroached_by(t2, P3)
        tv = tri.tv[t2]
        for k in range(3):  # on a border edge (within the snapping tolerance of insert): split it
            p, q = tv[(k + 1) % 3], tv[(k + 2) % 3]
            a, b = tri.uv[p], tri.uv[q]
            l2 = (b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2
            if tri.is_constrained(p, q) and orient(a, b, uv) <= 1e-9 * l2 and (p, q) not in enc:
                enc.append((p, q))
        if enc:
            for p, q in enc:
                self.split_segment(p, q)
            self._requeue(t)
            return True
        before = tuple(tri.tv[t])
        vnew = tri.add_vertex(uv, P3)
        tri.insert(vnew, t2)
        self.inserted += 1
        if tri.alive[t] and tuple(tri.tv[t]) == before:
            # no flip could remove t (the quad was not convex in (u, v)): try it again; the point
            # is now a vertex, so the next attempt takes the centroid
            self._requeue(t)
        return True

    def _requeue(self, t: int) -> None:
        if self.tri.alive[t]:
            self.pending.append(t)

    def encroached_by(self, t0: int, P: tuple[float, float, float]) -> list[tuple[int, int]]:
        tri = self.tri
        seen = {t0}
        stack = [t0]
        out: list[tuple[int, int]] = []
        while stack and len(seen) < 400:
            t = stack.pop()
            tv = tri.tv[t]
            for k in range(3):
                p, q = tv[(k + 1) % 3], tv[(k + 2) % 3]
                if tri.is_constrained(p, q):
                    if _dot_sub(tri.p3[p], P, tri.p3[q], P) < 0:
                        out.append((p, q))
                    continue
                n = tri.tn[t][k]
                if n < 0 or n in seen:
                    continue
                if self.in_cylinder(n, P, height=False):
                    seen.add(n)
                    stack.append(n)
        return out


def _d2(A: tuple, B: tuple) -> float:
    return (A[0] - B[0]) ** 2 + (A[1] - B[1]) ** 2 + (A[2] - B[2]) ** 2


def _dot_sub(A: tuple, P: tuple, B: tuple, Q: tuple) -> float:
    return (A[0] - P[0]) * (B[0] - Q[0]) + (A[1] - P[1]) * (B[1] - Q[1]) + (A[2] - P[2]) * (B[2] - Q[2])

"""Sharp creases that a hole interrupts, and the chains that continue them across the hole.

**(choice)**, not in spec/repair.md: a hole cut across a sharp crease (a CAD edge) is darned as a
smooth patch by §6 step 4, which rounds the crease off. Here the crease is continued first: every
sharp input edge (dihedral angle above ``angle`` degrees) that ends on the hole border gives a
crease end (its border vertex and the crease direction into the hole); two crease ends of one hole
whose directions point at each other are joined by a chain (a cubic Hermite curve with the two
crease directions as its end tangents), which splits the hole like any split bridge. The chain
vertices are then held fixed by the fairing, so each side is faired as its own smooth surface and
the crease stays sharp. Three crease ends whose rays meet at one point (a corner of the part)
are joined through that point.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .bridge_graph import resample_chain, segment_distance
from .holes import best_fit_plane
from .mesh import face_normals
from .topology import edge_table, face_adjacency


@dataclass(frozen=True, eq=False)
class CreaseEnds:
    """Sharp input edges by their vertices: for every vertex, the directions of the sharp edges
    that end there (unit vectors from the other end to the vertex) and those other ends."""

    directions: dict[int, list[NDArray[np.float64]]]
    others: dict[int, list[int]]
    normals: dict[int, list[NDArray[np.float64]]]  # (2, 3): the normals of the edge's two faces
    circles: dict[int, list[Circle | None]] = field(default_factory=dict)  # a curved crease's circle
    planes: dict[int, NDArray[np.float64]] = field(default_factory=dict)  # (P, 3) face planes at a vertex
    edges: dict[int, list[NDArray[np.float64]]] = field(default_factory=dict)  # normal pairs of all sharp edges
    moved: dict[int, set[int]] = field(default_factory=dict)  # border vertex -> the ends ``at`` moved to it
    followed: set[int] = field(default_factory=set)  # ends whose crease the border follows into another (``at``)
    joined: set[frozenset[int]] = field(default_factory=set)  # pairs of border vertices a crease chain joins

    def at(self, polygon: tuple[int, ...], V: NDArray[np.float64] | None = None,
           along: float = 12.0) -> list[tuple[int, NDArray[np.float64], NDArray[np.float64], Circle | None]]:
        """(position, direction, face normals, circle) of the crease ends on a hole polygon: sharp
        edges that reach the polygon from outside it (an edge between two polygon vertices runs
        along the border). With ``V``: where the border itself goes on along the crease (the next
        border vertex within ``along`` degrees of the crease direction), the end moves along it, so
        that no chain starts beside a border edge that already continues the crease; a straight
        end that moved leaves along the border's last edge (a tessellated rim read as straight
        turns on along the border: trimesh's subdivided cylinder, whose chain from two moved ends
        kept the directions of the sides they came from and met at a corner off the rim). Along a
        fine rim (``_fine``: at most FINE degrees of its circle per border edge) the direction turns
        with the circle at each step, the walk steps over a notch of the border (the next vertex off
        the circle, the one after on it: the mushroom's stem rim of bench/sweep.py cut 10:1, every
        other border vertex on the rim; the end stopped at the first notch and the arc from there,
        passing the border vertices on the rim beyond, was refused: 3.6 -> 0.66 % of the diagonal),
        and a curved end that moved leaves along the circle's tangent where it stopped. On a coarse
        circle (a 36-gon hole's 10 degrees) both stay as they were: with them, the walks of
        featuretype's hole rims went round their holes (cut 3:1: 2.6 -> 4.4 %; 8:1 full: 16 %)."""
        on = set(polygon)
        out = [(k, d, n, c) for k, v in enumerate(polygon)
               for d, w, n, c in zip(self.directions.get(int(v), ()), self.others.get(int(v), ()),
                                     self.normals.get(int(v), ()), self.circles.get(int(v), _nones()))
               if w not in on]
        if V is None:
            return out
        m, lim = len(polygon), np.cos(np.radians(along))
        starts = {k for k, *_ in out}
        moved = []
        for k, d, n, c in out:
            k0 = prev = k
            t = tangent(V[polygon[k]], d, c)  # a curved crease leaves along its circle's tangent
            for _ in range(m):  # sequential: walk while the border follows the crease
                step = [k2 for k2 in ((k + 1) % m, (k - 1) % m)
                        if float(t @ _unit(V[polygon[k2]] - V[polygon[k]])) > lim]
                edges = 1
                if not step and c is not None:  # over a notch, to the next border vertex on a fine rim
                    edges, step = 2, [k2 for k2 in ((k + 2) % m, (k - 2) % m)
                                      if _on_circle(V[polygon[k2]], c) and _fine(_dist(V, polygon, k, k2), c, 2)
                                      and float(t @ _unit(V[polygon[k2]] - V[polygon[k]])) > lim]
                if not step:
                    break
                if c is not None and _fine(_dist(V, polygon, k, step[0]), c, edges):
                    t = tangent(V[polygon[step[0]]], t, c)  # along a fine rim the direction turns with it
                prev, k = k, step[0]
            if k != k0 and _curve_to(V, polygon, prev, k, lim, starts - {k0}):
                self.followed.add(int(polygon[k0]))
                continue  # the border goes on as the crease into another end: it is the crease already
            if polygon[k] != polygon[k0]:
                self.moved.setdefault(int(polygon[k]), set()).add(int(polygon[k0]))
                if c is None:  # it leaves where the border turned away: along the border's last edge
                    d = _unit(V[polygon[k]] - V[polygon[prev]])
                else:  # along its circle from there
                    d = t
            moved.append((k, d, n, c))
        return moved

    def use(self, v: int) -> None:
        """A crease end that has been continued: no other chain starts there (nor from the ends
        that were moved to it along the border)."""
        for w in self.moved.pop(int(v), ()):
            self.use(w)
        for table in (self.directions, self.others, self.normals, self.circles):
            table.pop(int(v), None)
        # the face planes stay: another edge of a corner may still be missing there (crease_line
        # does not follow a ray along which the border, e.g. this chain, already runs)


def _curve_to(V: NDArray[np.float64], polygon: tuple[int, ...], prev: int, k: int, lim: float,
              ends: set[int]) -> bool:
    """Whether the border, walked on from polygon position k (arrived from ``prev``) with each edge
    within acos(``lim``) of the one before, reaches one of the positions ``ends`` (another crease
    end): a tessellated curve turns a little at every vertex (a subdivided 48-gon rim: walked
    against the crease's first direction, the two ends of a hole along it stopped 12 degrees round,
    and were joined by a chain bulging 5 % outside the rim)."""
    m = len(polygon)
    for _ in range(m):  # sequential: a walk
        if k in ends:
            return True
        t = _unit(V[polygon[k]] - V[polygon[prev]])
        nxt = (2 * k - prev) % m  # on along the border, the way the walk came
        if float(t @ _unit(V[polygon[nxt]] - V[polygon[k]])) <= lim:
            return False
        prev, k = k, nxt
    return False


def _dist(V: NDArray[np.float64], polygon: tuple[int, ...], i: int, j: int) -> float:
    return float(np.linalg.norm(V[polygon[j]] - V[polygon[i]]))


def _fine(chord: float, c: Circle, edges: int = 1) -> bool:
    """Whether a chord of circle c this long spans at most ``edges`` edges of a fine rim: at most
    FINE degrees of the circle per edge."""
    return chord <= 2 * c.radius * np.sin(np.radians(FINE * edges / 2))


def _miss(p: NDArray[np.float64], c: Circle) -> float:
    """How far points p (N, 3) lie off circle c at worst: the larger of |distance to its centre -
    radius| and the distance off its plane."""
    q = np.asarray(p, dtype=np.float64).reshape(-1, 3) - c.center
    return float(max(np.abs(np.linalg.norm(q, axis=1) - c.radius).max(), np.abs(q @ c.axis).max()))


def _on_circle(p: NDArray[np.float64], c: Circle, tol: float = 0.01) -> bool:
    """Whether point p lies on circle c, within ``tol`` of its radius (``_miss``)."""
    return _miss(p, c) <= tol * c.radius


def _nones():
    while True:
        yield None


@dataclass(frozen=True)
class Circle:
    """A curved crease's circle: centre, radius and unit axis (the normal of its plane)."""

    center: NDArray[np.float64]
    radius: float
    axis: NDArray[np.float64]

    def same(self, other: Circle, tol: float = 0.05, max_tilt: float = 10.0) -> bool:
        r = max(self.radius, other.radius)
        return bool(np.linalg.norm(self.center - other.center) < tol * r and abs(self.radius - other.radius) < tol * r
                    and abs(float(self.axis @ other.axis)) > np.cos(np.radians(max_tilt)))


def circumcircle(a: NDArray[np.float64], b: NDArray[np.float64], c: NDArray[np.float64]) -> Circle | None:
    """The circle through three points (None when they are collinear)."""
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = float(n @ n)
    if nn <= 1e-24 * max(float(ab @ ab), float(ac @ ac)) ** 2:
        return None
    center = a + (float(ac @ ac) * np.cross(n, ab) + float(ab @ ab) * np.cross(ac, n)) / (2 * nn)
    return Circle(center, float(np.linalg.norm(center - a)), n / np.sqrt(nn))


def fit_circle(points: NDArray[np.float64]) -> Circle | None:
    """The least-squares circle of points (N >= 3): in their least-squares plane, the algebraic fit
    x^2 + y^2 + D x + E y + F = 0 (Kasa); None when they are (nearly) collinear."""
    c, n = best_fit_plane(points)
    e1 = _unit(points[-1] - points[0] - ((points[-1] - points[0]) @ n) * n)
    e2 = np.cross(n, e1)
    q = points - c
    x, y = q @ e1, q @ e2
    if np.ptp(y) <= 1e-9 * max(float(np.ptp(x)), 1e-300):
        return None  # collinear: no plane, no circle
    A = np.stack([x, y, np.ones_like(x)], axis=1)
    sol, *_ = np.linalg.lstsq(A, -(x * x + y * y), rcond=None)
    cx, cy = -sol[0] / 2, -sol[1] / 2
    r2 = cx * cx + cy * cy - sol[2]
    span = float(np.linalg.norm(points[-1] - points[0]))
    if not np.isfinite(r2) or r2 <= 0 or np.sqrt(r2) > 1e6 * max(span, 1e-300):
        return None
    return Circle(c + cx * e1 + cy * e2, float(np.sqrt(r2)), n)


def _unit(a: NDArray[np.float64]) -> NDArray[np.float64]:
    n = float(np.linalg.norm(a))
    return a / n if n > 0 else a


def _shared(n1: NDArray[np.float64], n2: NDArray[np.float64], cos_lim: float) -> int:
    """How many of the two face normals of one crease end match one of the other's (0, 1 or 2)."""
    m = n1 @ n2.T  # (2, 2) cosines
    if m[0, 0] > cos_lim and m[1, 1] > cos_lim or m[0, 1] > cos_lim and m[1, 0] > cos_lim:
        return 2
    return int((m > cos_lim).any())


def sharp_edges(vertices: NDArray[np.float64], faces: NDArray[np.int64],
                angle: float) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """(K, 2) manifold edges whose two faces meet at a dihedral angle above ``angle`` degrees, and
    (K, 2, 3) the unit normals of their two faces."""
    f = np.asarray(faces, dtype=np.int64)
    if not len(f):
        return np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2, 3))
    fn = face_normals(vertices, f)
    pairs = face_adjacency(f)
    cos = np.einsum("ij,ij->i", fn[pairs[:, 0]], fn[pairs[:, 1]])
    sharp = pairs[cos < np.cos(np.radians(angle))]
    a, b = f[sharp[:, 0]], f[sharp[:, 1]]
    common = (a[:, :, None] == b[:, None, :]).any(axis=2)  # the two shared vertices of each pair
    e = a[common].reshape(-1, 2)
    return e, np.stack([fn[sharp[:, 0]], fn[sharp[:, 1]]], axis=1)


def _blocking(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """(vertex, unit normal) of every corner of every face: the faces around each vertex."""
    f = np.asarray(faces, dtype=np.int64)
    return f.ravel(), np.repeat(face_normals(vertices, f), 3, axis=0)


# crease_ends: a curved crease's circle is fitted to its longest stretch of LONG_FIT points or more
# (up to ``run`` edges back from its end) that one circle fits within FIT of its radius
LONG_FIT, FIT = 6, 0.005
# crease_ends: an end straight over its last three points is curved when its long stretch fits a
# circle and the chord of that stretch misses some point by LINE times the circle's worst miss
LINE = 10.0
# CreaseEnds.at: a fine rim turns by at most this many degrees per border edge (the mushroom's stem
# rim 1.4, the annulus' 0.9; not a 36-gon hole's 10): along one, a curved end's walk turns with the
# circle and steps over notches of the border
FINE = 3.0
# crease_split: an arc longer than this (degrees) is the long way round: two ends of a fillet whose
# short arc is still there, each continuing its circle into the hole (featuretype, sweep cut 8:1
# light: a 270 degree arc round a pocket's corner fillet, 3.5 -> 10.5 % of the diagonal)
MAX_ARC = 180.0


def crease_ends(vertices: NDArray[np.float64], faces: NDArray[np.int64], angle: float, *,
                corner: float = 0.5, min_bend: float = 3.0, max_bend: float = 40.0, run: int = 32) -> CreaseEnds:
    """The crease ends of the sharp input edges (``sharp_edges``): at each end vertex, the edge's
    direction going on past it.

    - An edge that ends at a corner of the part does not go on: when a face at the vertex faces
      along the direction (|n . d| above ``corner``; the faces along a crease that merely stops at
      the hole all contain d, so their normals are across it), a third surface closes the crease
      there, and the vertex gives no crease end for it.
    - A curved crease (the sharp edge before it turns by ``min_bend`` to ``max_bend`` degrees, and
      the edge before that, where there is one, lies on the same circle) carries a circle: it is
      continued along that circle, never straight. The circle is the one through its last three
      vertices, unless a longer stretch of the crease (LONG_FIT points or more, up to ``run``
      edges back) lies on one circle within FIT of its radius: then that one. Three points alone
      read the noise of a finely tessellated rim: the mushroom's 256-gon stem rim of bench/sweep.py
      (1.4 degrees an edge, points off the circle by 1e-3 of its radius) gave circles a quarter its
      size, and the two ends of one arc of the fandisk's 0.69 circle read radii 0.52 and 0.77.
    - A crease straight over its last three vertices is curved too when its longer stretch fits
      one circle within FIT and its chord misses a point by LINE times the circle's worst miss: a
      polygonal rim whose sides are cut into collinear pieces (the sweep's annulus, a 96-gon
      subdivided twice: the ends of a hole along the rim went on straight and their chain cut the
      rim's corner). A straight crease whose points are off the line fits a circle about as well
      as the line, and stays straight.
    - ``planes``: the distinct face normals at every vertex; ``edges``: the normal pairs of every
      sharp edge at a vertex (corners included), to find edges a hole removed whole.
    """
    out: dict[int, list[NDArray[np.float64]]] = {}
    oth: dict[int, list[int]] = {}
    nrm: dict[int, list[NDArray[np.float64]]] = {}
    circ: dict[int, list[Circle | None]] = {}
    pairs: dict[int, list[NDArray[np.float64]]] = {}
    planes: dict[int, NDArray[np.float64]] = {}
    edges, fn = sharp_edges(vertices, faces, angle)
    if not len(edges):
        return CreaseEnds(out, oth, nrm, circ, planes, pairs)
    fv, fvn = _blocking(vertices, faces)
    order = np.argsort(fv, kind="stable")
    fv, fvn = fv[order], fvn[order]
    start = np.searchsorted(fv, np.arange(len(vertices) + 1))
    nbr: dict[int, list[int]] = {}
    for a, b in edges.tolist():
        nbr.setdefault(a, []).append(b)
        nbr.setdefault(b, []).append(a)
    lo, hi = np.cos(np.radians(min_bend)), np.cos(np.radians(max_bend))

    def before(w: int, v: int) -> int | None:
        """The sharp edge's neighbour at w that continues the chain ... -> w -> v most straight."""
        d = _unit(vertices[v] - vertices[w])
        best = max(((float(_unit(vertices[w] - vertices[u]) @ d), u) for u in nbr.get(w, ()) if u != v),
                   default=None)
        return best[1] if best is not None and best[0] > hi else None

    def circle(v: int, w: int) -> Circle | None:
        u = before(w, v)
        if u is None:
            return None
        if float(_unit(vertices[w] - vertices[u]) @ _unit(vertices[v] - vertices[w])) > lo:
            # straight at its end: a polygon whose sides are split into collinear pieces (the
            # sweep's annulus, a 96-gon rim cut four times per side) still lies on a circle
            return long_fit([v, w, u], curved=True)
        c = circumcircle(vertices[u], vertices[w], vertices[v])
        t = before(u, w)
        if c is None or t is None:  # a fourth point on the same circle, else a kink, not an arc
            return None
        if _miss(vertices[t], c) > 0.02 * c.radius:
            return None
        return long_fit([v, w, u, t]) or c

    def long_fit(chain: list[int], curved: bool = False) -> Circle | None:
        """The same crease further back (up to ``run`` edges, each turning by at most max_bend):
        the circle (least-squares) of its longest stretch of at least LONG_FIT points that it fits
        within FIT of its radius. ``curved``: only a stretch whose chord misses one of its points by
        LINE times the circle's worst miss (a line would fit it far worse)."""
        while len(chain) <= run:
            x = before(chain[-1], chain[-2])
            if x is None or x in chain:
                break
            chain.append(x)
        for n in range(len(chain), LONG_FIT - 1, -1):
            p = vertices[chain[:n]]
            fit = fit_circle(p)
            if fit is None:
                continue
            off = _miss(p, fit)
            if off > FIT * fit.radius:
                continue
            if curved:
                d = _unit(p[-1] - p[0])
                q = p - p[0]
                if np.linalg.norm(q - np.outer(q @ d, d), axis=1).max() < LINE * max(off, 1e-12 * fit.radius):
                    continue  # a line fits about as well: straight, the circle is noise
            return fit
        return None

    # only vertices on the surface's border can be crease ends (a hole interrupts the crease there)
    et = edge_table(np.asarray(faces, dtype=np.int64))
    border = np.zeros(len(vertices) + 1, dtype=bool)
    border[et.edges[et.counts == 1].ravel()] = True
    for v in {int(x) for x in edges.ravel() if border[x]}:
        fvn_v = fvn[start[v]:start[v + 1]]
        keep: list[NDArray[np.float64]] = []
        for n in fvn_v:
            if all(float(n @ m) < 0.999 for m in keep):
                keep.append(n)
        planes[v] = np.array(keep)
    for (a, b), nn in zip(edges.tolist(), fn):
        d = vertices[a] - vertices[b]
        n = float(np.linalg.norm(d))
        if n <= 0:
            continue
        for v, w, dv in ((a, b, d / n), (b, a, -d / n)):
            if not border[v]:
                continue
            pairs.setdefault(v, []).append(nn)
            if np.abs(fvn[start[v]:start[v + 1]] @ dv).max(initial=0.0) > corner:
                continue  # a corner: the crease ends at v
            out.setdefault(v, []).append(dv)
            oth.setdefault(v, []).append(w)
            nrm.setdefault(v, []).append(nn)
            circ.setdefault(v, []).append(circle(v, w))
    return CreaseEnds(out, oth, nrm, circ, planes, pairs)


def missing_edges(ends: CreaseEnds, v: int,
                  angle: float = 40.0) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """Edges of a corner that a hole removed whole: (direction, (2, 3) normals) for every two
    face planes at ``v`` that meet at more than ``angle`` degrees but have no sharp edge at v
    between them; both directions along the line where the planes meet (the caller keeps the one
    that runs over the hole to another border vertex)."""
    P = ends.planes.get(int(v))
    if P is None or len(P) < 3:
        return []
    have = ends.edges.get(int(v), [])
    lim = np.cos(np.radians(angle))
    out = []
    for x in range(len(P)):
        for y in range(x + 1, len(P)):
            if float(P[x] @ P[y]) > lim:
                continue
            pair = np.stack([P[x], P[y]])
            if any(_shared(pair, h, 0.99) == 2 for h in have):
                continue
            d = _unit(np.cross(P[x], P[y]))
            out += [(d, pair), (-d, pair)]
    return out


def hermite(p0: NDArray[np.float64], d0: NDArray[np.float64], p1: NDArray[np.float64], d1: NDArray[np.float64],
            spacing: float, lead: tuple[float, float] = (0.0, 0.0), least: int = 1) -> NDArray[np.float64]:
    """Interior points of the cubic Hermite curve from p0 (tangent d0) to p1 (tangent d1), tangents
    scaled by the chord length, evenly about ``spacing`` apart along the curve; at least one (a
    chain without interior points would be a chord that may already be an edge of the surface).
    ``lead``: the arc lengths the first and last points keep from p0 and p1 at least
    (``end_clearance``; ``spaced_chain``, with ``least``: 0 lets a curve whose end is a new chain vertex
    have none)."""
    L = float(np.linalg.norm(p1 - p0))
    t = np.linspace(0.0, 1.0, 65)[:, None]  # dense, then resampled by arc length
    h00, h10, h01, h11 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t, -2 * t**3 + 3 * t**2, t**3 - t**2
    curve = h00 * p0 + h10 * L * d0 + h01 * p1 + h11 * L * d1
    length = float(np.linalg.norm(np.diff(curve, axis=0), axis=1).sum())
    return spaced_chain(curve, min(spacing, length / 2), lead, least=least)


def spaced_chain(curve: NDArray[np.float64], spacing: float, lead: tuple[float, float] = (0.0, 0.0), *,
                 least: int = 1) -> NDArray[np.float64]:
    """Interior points of the polyline ``curve`` about ``spacing`` apart by arc length
    (bridge_graph.resample_chain), the first at least ``lead[0]`` from its start and the last at least
    ``lead[1]`` from its end (``end_clearance``). No lead longer than the even step: resample_chain's
    points exactly. Otherwise that end's point moves out to its lead and the points between are
    spaced evenly again; where the room left is under half the spacing: with both leads, one point
    midway between them; with one, no point when ``least`` is 0 (the curve's other end is a new chain
    vertex, e.g. a corner point), else one at the lead, kept a quarter of the curve from either end."""
    p = np.asarray(curve, dtype=np.float64)
    even = resample_chain(p, spacing)
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    total = float(seg.sum())
    step = total / (len(even) + 1)
    if total <= 0 or (lead[0] <= step and lead[1] <= step):
        return even
    start = float(lead[0]) if lead[0] > step else 0.0
    stop = total - float(lead[1]) if lead[1] > step else total
    if stop - start < 0.5 * spacing:  # no room for the points between
        if start > 0 and stop < total:
            t = np.array([(start + stop) / 2])
        elif not least:
            return np.zeros((0, 3))
        else:
            t = np.array([start if start > 0 else stop])
        t = np.clip(t, 0.25 * total, 0.75 * total)
    else:
        t = np.linspace(start, stop, max(1, int(round((stop - start) / spacing))) + 1)
        t = t[1 if start == 0.0 else 0:len(t) - 1 if stop == total else len(t)]  # the ends are vertices
    s = np.concatenate([[0.0], np.cumsum(seg)])
    return np.stack([np.interp(t, s, p[:, k]) for k in range(3)], axis=1)


def end_clearance(V: NDArray[np.float64], polygon: tuple[int, ...], k: int, d: NDArray[np.float64], *,
                  min_angle: float = 22.0) -> float:
    """How far along its direction ``d`` (unit, into the hole) the first vertex of a chain leaving
    polygon position k must lie: 0 unless a border edge (e, w) at the chain's end e makes an angle
    theta < 2 ``min_angle`` with d. Such a wedge holds one patch face only (a second face at e would
    halve theta, below ``min_angle``), and with both its edges fixed (a kept border edge, a locked
    crease chain edge) that face is (e, c, w), c the chain's first vertex: by the law of sines its
    angle at w is at least ``min_angle`` once |e c| >= |e w| sin(min_angle) / sin(pi - theta -
    min_angle). A chain vertex at the even spacing beside a long border edge made it a sliver
    (featuretype: a crease end beside a 0.93 border edge at 19.3 degrees, the first vertex 0.31 along:
    a 7.1 degree angle at the edge's far end on each side of the crease). Default 22 degrees: the
    angle refinement's bound and its margin (darning.refine.refine_angles)."""
    n = len(polygon)
    e = V[polygon[k]]
    t = np.radians(min_angle)
    need = 0.0
    for w in (polygon[(k - 1) % n], polygon[(k + 1) % n]):
        u = V[w] - e
        L = float(np.linalg.norm(u))
        if L <= 0:
            continue
        theta = float(np.arctan2(np.linalg.norm(np.cross(u, d)), u @ d))
        if theta < 2 * t:
            need = max(need, L * np.sin(t) / np.sin(np.pi - theta - t))
    return need


Valid = Callable[[int, int, NDArray[np.float64]], bool]  # (position i, position j or -1, chain points)


@dataclass(frozen=True)
class CreaseSplit:
    """Split a hole polygon at positions i and j by a chain through ``points`` (interior points)."""

    i: int
    j: int
    points: NDArray[np.float64]
    quality: float  # how well the two directions point at each other (2 = exactly)


class Surface:
    """The input surface a crease chain must not run over: a chain continues a crease across the
    hole, so apart from its two end vertices it lies in the hole, never on an input face (a chain
    on a face, e.g. two crease rays that meet beyond the hole's border, crosses the border and
    makes a self-overlapping decomposition: featuretype's corner chain ran 0.9 units over the top
    face)."""

    def __init__(self, vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> None:
        f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        et = edge_table(f)
        inner = np.zeros(len(vertices), dtype=bool)
        inner[np.unique(f)] = True
        inner[et.edges[et.counts == 1].ravel()] = False
        self.v = np.asarray(vertices, dtype=np.float64)[inner]  # inside the surface: faces all around
        self.t = np.asarray(vertices, dtype=np.float64)[f]  # (F, 3, 3)
        self.lo, self.hi = self.t.min(axis=1), self.t.max(axis=1)
        self._tree = None

    def covers(self, points: NDArray[np.float64], tol: float, margin: float = 0.02) -> NDArray[np.bool_]:
        """(K,) whether each point lies within ``tol`` of an input face and projects strictly inside
        it (every barycentric coordinate above ``margin``: a point beside the hole's border edge
        projects onto that edge, not inside the face)."""
        q = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        out = np.zeros(len(q), dtype=bool)
        for s0 in range(0, len(q), 64):  # chunks of points against every face's box at once
            x = q[s0:s0 + 64]
            near = np.all((self.lo[None] - tol <= x[:, None]) & (x[:, None] <= self.hi[None] + tol), axis=2)
            pi, fi = np.nonzero(near)
            if not len(pi):
                continue
            t = self.t[fi]
            e0, e1, w = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0], x[pi] - t[:, 0]
            n = np.cross(e0, e1)
            nn = np.linalg.norm(n, axis=1)
            h = np.abs(np.einsum("ij,ij->i", w, n)) / np.maximum(nn, 1e-300)
            d00, d01, d11 = (e0 * e0).sum(1), (e0 * e1).sum(1), (e1 * e1).sum(1)
            d20, d21 = (w * e0).sum(1), (w * e1).sum(1)
            den = np.maximum(d00 * d11 - d01 * d01, 1e-300)
            a = (d11 * d20 - d01 * d21) / den
            b = (d00 * d21 - d01 * d20) / den
            hit = (nn > 0) & (h <= tol) & (a > margin) & (b > margin) & (1 - a - b > margin)
            out[s0 + pi[hit]] = True
        return out

    def crossed_by(self, p0: NDArray[np.float64], pts: NDArray[np.float64], p1: NDArray[np.float64],
                   tol: float, step: float) -> bool:
        """Whether the chain p0 -> pts -> p1, sampled about ``step`` apart, runs over an input face."""
        poly = np.vstack([p0[None], np.asarray(pts).reshape(-1, 3), p1[None]])
        dense = [poly[:1]]
        for a, b in zip(poly[:-1], poly[1:]):
            k = max(1, int(np.ceil(float(np.linalg.norm(b - a)) / max(step, 1e-12))))
            dense.append(a + (b - a) * (np.arange(1, k + 1)[:, None] / k))
        x = np.vstack(dense)[1:-1]
        return bool(len(x) and self.covers(x, tol).any())

    def touched_by(self, p0: NDArray[np.float64], pts: NDArray[np.float64], p1: NDArray[np.float64],
                   tol: float) -> bool:
        """Whether the chain p0 -> pts -> p1 comes within ``tol`` of an input vertex that is not on
        a border (faces all around it: on the surface, never in a hole), other than at its two
        ends: a chain along input edges runs on the surface without crossing a face's inside
        (trimesh's cone without two wedges of side slivers: an arc of its base rim from one wedge
        to the other ran along the rim still there, over a quarter of the circle). Border vertices
        are the callers' (a box's edge rebuilt from corner to corner passes the border vertices
        where the hole reaches the edge)."""
        from scipy.spatial import cKDTree

        poly = np.vstack([p0[None], np.asarray(pts, dtype=np.float64).reshape(-1, 3), p1[None]])
        if self._tree is None:
            self._tree = cKDTree(self.v)
        mid, half = (poly[:-1] + poly[1:]) / 2, np.linalg.norm(np.diff(poly, axis=0), axis=1) / 2
        near = np.unique(np.concatenate([np.asarray(i, dtype=np.int64)
                                         for i in self._tree.query_ball_point(mid, half + tol)]))
        q = self.v[near]
        q = q[(np.linalg.norm(q - p0, axis=1) > tol) & (np.linalg.norm(q - p1, axis=1) > tol)]
        return passes_near(p0, pts, p1, q, tol)


def passes_near(p0: NDArray[np.float64], pts: NDArray[np.float64], p1: NDArray[np.float64],
                points: NDArray[np.float64], tol: float) -> bool:
    """Whether the chain p0 -> pts -> p1 comes within ``tol`` of one of ``points`` (segment to
    point distances, so a point between two samples counts)."""
    poly = np.vstack([p0[None], np.asarray(pts, dtype=np.float64).reshape(-1, 3), p1[None]])
    q = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not len(q):
        return False
    a, d = poly[:-1], np.diff(poly, axis=0)  # (S, 3)
    lo, hi = np.minimum(poly[:-1], poly[1:]) - tol, np.maximum(poly[:-1], poly[1:]) + tol
    near = np.all((lo[:, None] <= q[None]) & (q[None] <= hi[:, None]), axis=2)  # (S, Q) box test first
    si, qi = np.nonzero(near)
    if not len(si):
        return False
    # a point is a segment of length zero
    return bool((segment_distance(a[si], a[si] + d[si], q[qi], q[qi]) <= tol).any())


def _interleaved(a: tuple[int, int], b: tuple[int, int]) -> bool:
    (i, j), (k, m) = sorted(a), sorted(b)
    return (i < k < j) != (i < m < j) and len({i, j, k, m}) == 4


def arc(p0: NDArray[np.float64], d0: NDArray[np.float64], p1: NDArray[np.float64], c: Circle,
        spacing: float, max_step: float = 20.0) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """Interior points of the arc of circle ``c`` from p0 (leaving along d0) to p1, about
    ``spacing`` apart and at most ``max_step`` degrees apart (so its chords stay near the circle),
    and the arc's direction of travel at p1; None when d0 does
    not run along the circle."""
    e1 = _unit(p0 - c.center)
    e2 = _unit(np.cross(c.axis, e1))
    if float(d0 @ e2) < 0:
        e2 = -e2
    if float(d0 @ e2) < np.cos(np.radians(30.0)):
        return None
    q = p1 - c.center
    phi = float(np.arctan2(q @ e2, q @ e1)) % (2 * np.pi)
    if phi < 1e-3:
        return None
    m = max(2, int(round(c.radius * phi / max(spacing, 1e-12))), int(np.ceil(phi / np.radians(max_step))))
    t = phi * np.arange(1, m)[:, None] / m
    h = (p0 - c.center) @ c.axis  # the end points' heights over the circle's plane, blended
    h1 = q @ c.axis
    pts = c.center + c.radius * (np.cos(t) * e1 + np.sin(t) * e2) + (h + (h1 - h) * t / phi) * c.axis
    return pts, -np.sin(phi) * e1 + np.cos(phi) * e2


def tangent(p: NDArray[np.float64], d: NDArray[np.float64], c: Circle | None) -> NDArray[np.float64]:
    """The direction in which a crease leaves its end p: d for a straight one; for a curved one
    the circle's tangent at p (d is the direction of its last chord, half a step off), the way
    a fillet ends tangent to the straight edge after it."""
    if c is None:
        return d
    t = _unit(np.cross(c.axis, p - c.center))
    return t if float(t @ d) >= 0 else -t


def _ends(V: NDArray[np.float64], polygon: tuple[int, ...], ends: CreaseEnds, max_turn: float = 25.0
          ) -> list[tuple[int, NDArray[np.float64], NDArray[np.float64], Circle | None]]:
    """The crease ends on ``polygon`` (CreaseEnds.at), curved ones resolved: a curved end whose
    circle leads to another end on the polygon (same circle, the arc arriving within ``max_turn``
    degrees of that end's crease, head-on) is a circle the hole interrupts (it keeps its circle:
    arc or nothing); any other curved end on its circle is an arc that ended (a fillet), and the
    crease goes on straight along its tangent (circle None)."""
    cand = ends.at(polygon, V)
    lim = np.cos(np.radians(max_turn))

    def joins(x: int, y: int) -> bool:  # the arc from end x along its crease arrives at end y head-on
        (k, d, _, c), (k2, d2, _, c2) = cand[x], cand[y]
        if y == x or c2 is None or k2 == k or not c.same(c2):
            return False
        got = arc(V[polygon[k]], d, V[polygon[k2]], c, 1.0)
        return got is not None and float(got[1] @ -d2) > lim

    out = []
    for x, (k, d, n, c) in enumerate(cand):
        if c is not None and not any(joins(x, y) for y in range(len(cand))):
            d, c = tangent(V[polygon[k]], d, c), None
        out.append((k, d, n, c))
    return out


def crease_split(V: NDArray[np.float64], polygon: tuple[int, ...], ends: CreaseEnds, spacing: float, *,
                 max_turn: float = 25.0, max_normal_turn: float = 40.0, arcs: bool = False,
                 valid: Valid | None = None) -> CreaseSplit | None:
    """The best crease chain across the hole ``polygon``, or None.

    A crease end is a polygon vertex with a sharp input edge ending there; its direction d must
    point into the hole. Straight ends i and j pair when the chord u from i to j is within
    ``max_turn`` degrees of d_i and of -d_j, and the two faces along the crease at i face like the
    two at j (within ``max_normal_turn`` degrees: the same two surfaces meet there); the best pair
    (largest d_i . u - d_j . u) is returned. Two curved ends (``Circle``) pair when they lie on one
    circle and the arc from i along d_i arrives at j along -d_j (within ``max_turn``); they are
    joined along the arc (quality 2) when ``arcs`` is on (the pipeline's choice, repair.py), else
    not at all. Otherwise a curved end goes on along its tangent.
    ``valid(i, j, points)``: a chain it refuses (e.g. one that runs over the input surface,
    ``Surface``) is not taken; the next best pair is.
    """
    cand = _ends(V, polygon, ends)
    if len(cand) < 2:
        return None
    lim = np.cos(np.radians(max_turn))
    nlim = np.cos(np.radians(max_normal_turn))
    found: list[tuple[float, int, int, NDArray[np.float64]]] = []
    n = len(polygon)
    for x in range(len(cand)):
        for y in range(x + 1, len(cand)):
            (i, di, ni, ci), (j, dj, nj, cj) = cand[x], cand[y]
            if min((i - j) % n, (j - i) % n) < 2:
                continue
            if arcs and ci is not None and cj is not None and ci.same(cj):
                if _shared(ni, nj, nlim) < 1:
                    continue
                got = arc(V[polygon[i]], di, V[polygon[j]], ci, spacing)
                if got is None or float(got[1] @ -dj) < lim:
                    continue
                path = np.vstack([V[polygon[i]], got[0], V[polygon[j]]])
                if float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum()) > np.radians(MAX_ARC) * ci.radius:
                    continue  # the long way round
                found.append((2.0 + float(got[1] @ -dj), i, j, got[0]))
                continue
            if _shared(ni, nj, nlim) < 2:
                continue
            if ci is not None or cj is not None:  # a circle the hole interrupts: never straight
                continue
            u = V[polygon[j]] - V[polygon[i]]
            L = float(np.linalg.norm(u))
            if L <= 0:
                continue
            u /= L
            a, b = float(di @ u), float(-dj @ u)
            if a > lim and b > lim:
                lead = (end_clearance(V, polygon, i, di), end_clearance(V, polygon, j, dj))
                found.append((a + b, i, j, hermite(V[polygon[i]], di, V[polygon[j]], -dj, spacing, lead)))
    for q, i, j, pts in sorted(found, key=lambda x: -x[0]):  # the best pair first (stable for ties)
        if valid is None or valid(i, j, pts):
            return CreaseSplit(int(i), int(j), pts, min(float(q), 2.0))
    return None


def _on_line(V: NDArray[np.float64], polygon: tuple[int, ...], p: NDArray[np.float64], d: NDArray[np.float64],
             skip: set[int], tol: float, both: bool = False) -> tuple[int, float] | None:
    """The nearest polygon position (not in ``skip``) on the ray p + t d, t > 0 (either way with
    ``both``), within ``tol`` times t of it: (position, t)."""
    w = V[list(polygon)] - p
    t = w @ d
    perp = np.linalg.norm(w - t[:, None] * d, axis=1)
    ok = (np.abs(t) if both else t) > 0
    ok &= perp <= tol * np.abs(t)
    ok[list(skip)] = False
    if not ok.any():
        return None
    k = int(np.flatnonzero(ok)[np.argmin(np.abs(t[ok]))])
    return k, float(t[k])


def crease_line(V: NDArray[np.float64], polygon: tuple[int, ...], ends: CreaseEnds, spacing: float, *,
                tol: float = 1e-3, valid: Valid | None = None) -> CreaseSplit | None:
    """A straight crease whose ray runs exactly through another border vertex (CAD edges: the
    other end has no sharp edge of its own pointing back, e.g. the edge of a corner that the hole
    removed whole, ``missing_edges``), or None. The nearest such pair that ``valid`` accepts wins."""
    n = len(polygon)
    rays = [(k, d) for k, d, _, c in _ends(V, polygon, ends) if c is None]
    rays += [(k, d) for k, v in enumerate(polygon) for d, _ in missing_edges(ends, v)]
    found = []
    for k, d in rays:
        nb = V[[polygon[(k - 1) % n], polygon[(k + 1) % n]]] - V[polygon[k]]
        if (nb @ d > (1 - tol) * np.linalg.norm(nb, axis=1)).any():
            continue  # the border (an earlier chain, a border edge) already runs along the ray
        hit = _on_line(V, polygon, V[polygon[k]], d, {(k + s) % n for s in (-1, 0, 1)}, tol)
        if hit is not None:
            found.append((hit[1], k, hit[0]))
    for _, i, j in sorted(found, key=lambda x: x[0]):
        u = _unit(V[polygon[j]] - V[polygon[i]])
        pts = spaced_chain(np.vstack([V[polygon[i]], V[polygon[j]]]), spacing,
                           (end_clearance(V, polygon, i, u), end_clearance(V, polygon, j, -u)))
        if not len(pts):
            pts = ((V[polygon[i]] + V[polygon[j]]) / 2)[None]
        if valid is None or valid(i, j, pts):
            return CreaseSplit(int(i), int(j), pts, 2.0)
    return None


def crease_corner(V: NDArray[np.float64], polygon: tuple[int, ...], ends: CreaseEnds, spacing: float, *,
                  max_miss: float = 0.15, rays: int = 3, min_turn: float = 30.0,
                  max_normal_turn: float = 30.0, tol: float = 1e-3, valid: Valid | None = None
                  ) -> tuple[CreaseSplit, int, NDArray[np.float64], NDArray[np.float64] | None] | None:
    """``rays`` (3 or 2) crease ends whose rays meet near one point C (a corner of the part): the
    split from the first end through C to the second (C is a vertex of its chain), the position of
    the third end (-1 when there is none: the crease turns at C), C, and the third edge's
    direction (towards C).

    The rays p_k + t d_k (t > 0) must pass within ``max_miss`` times their length to C of C; two
    rays must turn by at least ``min_turn`` degrees (straight ones are crease_split's). Every two
    of the rays must border one common surface (a face normal of each within ``max_normal_turn``
    degrees), as the edges of one corner do (curved ends: as ``_ends`` resolves them). For two rays,
    the corner's third edge runs where the two surfaces not shared meet: when a border vertex lies
    on that line through C (within ``tol`` times its distance), it is the third end.
    """
    from itertools import combinations

    cand = [e for e in _ends(V, polygon, ends) if e[3] is None]
    if len(cand) < rays:
        return None
    pts = V[list(polygon)]
    pad = 0.1 * float(np.linalg.norm(np.ptp(pts, axis=0)))
    lo, hi = pts.min(axis=0) - pad, pts.max(axis=0) + pad  # the corner lies over the hole
    best = None
    for combo in combinations(range(len(cand)), rays):  # few crease ends per hole
        tri = [cand[c] for c in combo]
        if len({k for k, _, _, _ in tri}) < rays:
            continue
        if rays == 2 and abs(float(tri[0][1] @ tri[1][1])) > np.cos(np.radians(min_turn)):
            continue
        nlim = np.cos(np.radians(max_normal_turn))
        if any(_shared(p[2], q[2], nlim) != 1 for p, q in combinations(tri, 2)):
            continue
        P = np.array([V[polygon[k]] for k, _, _, _ in tri])
        D = np.array([d for _, d, _, _ in tri])
        # least-squares point nearest the lines: sum (I - d d^T) (C - p) = 0
        A = sum(np.eye(3) - np.outer(d, d) for d in D)
        rhs = sum((np.eye(3) - np.outer(d, d)) @ p for d, p in zip(D, P))
        try:
            C = np.linalg.solve(A, rhs)
        except np.linalg.LinAlgError:
            continue
        t = np.einsum("ij,ij->i", C - P, D)
        if np.any(t <= 0) or np.any(C < lo) or np.any(C > hi):
            continue
        miss = np.linalg.norm(P + t[:, None] * D - C, axis=1) / t
        key = float(miss.max())  # the best meeting (the first found of equal ones)
        if key >= max_miss or (best is not None and key >= best[0]):
            continue
        # each leg to C must stay in the hole (``valid``: e.g. not over the input surface)
        legs = [hermite(V[polygon[k]], d, C, d, spacing) for k, d, _, _ in tri] if valid is not None else []
        if not all(valid(k, -1, np.vstack([lg, C[None]])) for (k, _, _, _), lg in zip(tri, legs)):
            continue
        best = (key, tri, C)
    if best is None:
        return None
    _, tri, C = best
    (i, di, ni, _), (j, dj, nj, _) = tri[:2]
    k, dk = (tri[2][0], tri[2][1]) if rays == 3 else (-1, None)
    if rays == 2:  # the third edge: the two normals that are not shared
        nlim = np.cos(np.radians(max_normal_turn))
        oi = [a for a in ni if not any(float(a @ b) > nlim for b in nj)]
        oj = [b for b in nj if not any(float(a @ b) > nlim for a in ni)]
        if len(oi) == 1 and len(oj) == 1 and abs(float(oi[0] @ oj[0])) < 0.9:
            e = _unit(np.cross(oi[0], oj[0]))
            hit = _on_line(V, polygon, C, e, {i, j}, tol, both=True)
            if hit is not None:
                k = hit[0]
                dk = _unit(C - V[polygon[k]])
    a = hermite(V[polygon[i]], di, C, di, spacing, (end_clearance(V, polygon, i, di), 0.0), least=0)
    b = hermite(C, -dj, V[polygon[j]], -dj, spacing, (0.0, end_clearance(V, polygon, j, dj)), least=0)
    pts = np.vstack([a, C[None], b])
    return CreaseSplit(int(i), int(j), pts, float(3 - 3 * best[0])), int(k), C, dk

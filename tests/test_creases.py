"""Crease continuation across holes (algorithms.creases) on boxes with known geometry."""

import numpy as np
import pytest
import trimesh

from algorithms.creases import Circle, circumcircle, crease_ends, tangent
from algorithms.mesh import Mesh
from algorithms.normalize import normalize
from algorithms.repair import RepairParams, repair
from algorithms.topology import boundary_loops

HALF = np.array([1.0, 0.75, 0.5])  # half extents of the box


def _box(levels: int = 3) -> Mesh:
    b = trimesh.creation.box(extents=2 * HALF)
    for _ in range(levels):
        b = b.subdivide()
    return Mesh(np.asarray(b.vertices, dtype=np.float64), np.asarray(b.faces, dtype=np.int64))


def _box_distance(p: np.ndarray) -> np.ndarray:
    """Unsigned distance of points to the surface of the box (analytic)."""
    q = np.abs(p) - HALF
    outside = np.linalg.norm(np.maximum(q, 0), axis=1)
    inside = np.minimum(q.max(axis=1), 0)
    return np.abs(outside + inside)


def _repaired(keep: np.ndarray, mode: str = "light"):
    box = _box()
    used = np.unique(box.faces[keep])
    remap = np.full(box.n_vertices, -1)
    remap[used] = np.arange(len(used))
    V, F = box.vertices[used], remap[box.faces[keep]]
    res = repair(normalize(V, F), RepairParams())
    return V, F, res


def test_circumcircle_and_tangent_are_exact():
    ang = np.radians([10.0, 40.0, 75.0])
    c0 = np.array([0.3, -1.0, 2.0])
    pts = c0 + 2.0 * np.stack([np.cos(ang), np.sin(ang), np.zeros(3)], axis=1)
    c = circumcircle(*pts)
    assert np.allclose(c.center, c0) and c.radius == pytest.approx(2.0)
    assert abs(abs(c.axis[2]) - 1) < 1e-12
    t = tangent(pts[2], np.array([-1.0, 0.2, 0.0]), c)  # continues counter-clockwise
    assert np.allclose(t, [-np.sin(ang[2]), np.cos(ang[2]), 0.0])
    assert circumcircle(pts[0], pts[0] + 1, pts[0] + 2) is None  # collinear
    assert Circle(c0, 2.0, np.array([0, 0, 1.0])).same(Circle(c0 + 0.01, 2.02, np.array([0, 0.05, 1.0])))


def test_corner_ends_point_at_the_corner_and_stop_at_corners():
    box = _box()
    corner = HALF.copy()
    cen = box.vertices[box.faces].mean(axis=1)
    keep = np.linalg.norm(cen - corner, axis=1) > 0.45
    F = box.faces[keep]
    ends = crease_ends(box.vertices, F, 40.0)
    loop = boundary_loops(F)[0]
    found = ends.at(tuple(int(v) for v in loop))
    assert len(found) == 3  # the three edges into the corner, nothing else (the other corners are whole)
    for k, d, _, circle in found:
        to_corner = corner - box.vertices[loop[k]]
        assert circle is None
        assert float(d @ to_corner / np.linalg.norm(to_corner)) > 1 - 1e-9


def test_box_corner_cut_off_comes_back_sharp():
    box = _box()
    cen = box.vertices[box.faces].mean(axis=1)
    keep = np.linalg.norm(cen - HALF, axis=1) > 0.45
    V, F, res = _repaired(keep)
    out = res.mesh
    diag = float(np.linalg.norm(2 * HALF))
    assert _box_distance(out.vertices).max() < 1e-3 * diag
    assert np.linalg.norm(out.vertices - HALF, axis=1).min() < 1e-3 * diag  # the corner itself is rebuilt
    tm = trimesh.Trimesh(out.vertices, out.faces, process=False)
    assert tm.is_watertight and tm.euler_number == 2


def _cad_box() -> tuple[np.ndarray, np.ndarray, int, int]:
    """A box triangulated as CAD exporters do (few large triangles): the top (z) and the +y side
    each have one inner point, so the corners A and B of their common edge AB also belong to
    triangles of both faces that do not touch AB. Returns (V, F, A, B)."""
    hx, hy, hz = HALF
    c = [(x, y, z) for x in (-hx, hx) for y in (-hy, hy) for z in (-hz, hz)]  # index = 4 ix + 2 iy + iz
    V = np.array(c + [(0.1, 0.2, hz), (-0.2, hy, 0.1)], dtype=np.float64)  # P on top, Q on the +y side
    P, Q = 8, 9
    A, B = 3, 7  # (-hx, hy, hz), (hx, hy, hz)
    F = [(A, B, P), (B, 5, P), (5, 1, P), (1, A, P),  # top z = hz: A B (hx,-hy,hz) (-hx,-hy,hz)
         (A, B, Q), (B, 6, Q), (6, 2, Q), (2, A, Q),  # side y = hy
         (0, 1, 3), (0, 3, 2), (4, 5, 7), (4, 7, 6), (0, 4, 5), (0, 5, 1), (0, 2, 6), (0, 6, 4)]
    F = np.array(F, dtype=np.int64)
    t = V[F]  # the box is convex and centred at 0: a face is wound outward when its normal points away
    out = np.einsum("ij,ij->i", np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), t.mean(axis=1)) > 0
    F[~out] = F[~out][:, ::-1]
    tm = trimesh.Trimesh(V, F, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    return V, F, A, B


def test_edge_a_hole_removed_whole_is_rebuilt_from_the_corner_planes():
    """The two triangles along AB removed: neither corner has a sharp edge pointing along AB, but
    the top and side planes meet at both corners without an edge between them (missing_edges): the
    ray from A along their intersection runs through B (crease_line), so AB comes back exactly."""
    V, F, A, B = _cad_box()
    along = np.array([sorted(f) in (sorted([A, B, 8]), sorted([A, B, 9])) for f in F.tolist()])
    res = repair(normalize(V, F[~along]), RepairParams())
    out = res.mesh
    assert _box_distance(out.vertices).max() < 1e-9
    crease = [b for b in res.bridges if b.kind == "crease"]
    assert len(crease) == 1
    on_edge = (np.abs(out.vertices[:, 1] - HALF[1]) < 1e-9) & (np.abs(out.vertices[:, 2] - HALF[2]) < 1e-9)
    assert on_edge.sum() >= 3  # A, B and the chain between them
    tm = trimesh.Trimesh(out.vertices, out.faces, process=False)
    assert tm.is_watertight and tm.euler_number == 2


def test_an_edge_removed_whole_beside_a_continued_crease_comes_back():
    """A ball around the middle of the box's vertical edge (x, y) = (hx, hy) removes that edge from
    corner to corner and the ends of the top and bottom edges at those corners: the top and bottom
    creases are continued to the corners first, and the corners keep their face planes, so the
    vertical edge (missing_edges + crease_line) is rebuilt too; the patch is the box exactly (the
    corners' planes were dropped with their used crease ends before: the vertical edge was rounded
    off, 0.082 units = 3 % of the diagonal) and its triangles are well shaped."""
    from algorithms.metrics import min_angles

    box = _box()
    cen = box.vertices[box.faces].mean(axis=1)
    keep = np.linalg.norm(cen - HALF * np.array([1.0, 1.0, 0.0]), axis=1) > 0.45
    V, F, res = _repaired(keep)
    out = res.mesh
    assert _box_distance(out.vertices).max() < 1e-9
    crease = [b for b in res.bridges if b.kind == "crease"]
    assert len(crease) == 3
    on_edge = (np.abs(out.vertices[:, 0] - HALF[0]) < 1e-9) & (np.abs(out.vertices[:, 1] - HALF[1]) < 1e-9)
    assert on_edge.sum() >= 3  # the two corners and the vertical chain between them
    ang = min_angles(out.vertices, out.faces[res.new_faces])
    assert ang.min() >= 15.0
    tm = trimesh.Trimesh(out.vertices, out.faces, process=False)
    assert tm.is_watertight and tm.euler_number == 2


def test_surface_covers_points_on_faces_not_beside_the_border():
    """creases.Surface: a point on an input face (strictly inside it) is covered, a point in the
    hole or on the extension of a border edge is not; a chain over the surface is refused."""
    from algorithms.creases import Surface

    g = np.stack(np.meshgrid(np.arange(4.0), np.arange(4.0), indexing="ij"), axis=-1).reshape(-1, 2)
    V = np.c_[g, np.zeros(len(g))]
    idx = np.arange(16).reshape(4, 4)
    F = [(idx[i, j], idx[i + 1, j], idx[i + 1, j + 1]) for i in range(3) for j in range(3)]
    F += [(idx[i, j], idx[i + 1, j + 1], idx[i, j + 1]) for i in range(3) for j in range(3)]
    F = np.array([f for f in F if not np.allclose(V[list(f)].mean(axis=0)[:2], [1.5, 1.5], atol=0.5)])
    s = Surface(V, F)  # the unit square (1..2, 1..2) is the hole
    got = s.covers(np.array([[0.4, 0.3, 0.0], [1.5, 1.5, 0.0], [1.5, 1.0, 0.0], [0.4, 0.3, 0.5]]), tol=1e-6)
    assert got.tolist() == [True, False, False, False]
    a, b = V[idx[1, 1]], V[idx[2, 2]]
    assert not s.crossed_by(a, ((a + b) / 2)[None], b, 1e-6, 0.1)  # the diagonal across the hole
    c = V[idx[3, 2]]
    assert s.crossed_by(a, ((a + c) / 2)[None], c, 1e-6, 0.1)  # across the hole, then over the faces x > 2


def _wedge_angle_at_w(e, c, w):
    u, v = e - w, c - w
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(u, v)), u @ v))


def test_end_clearance_gives_the_far_corner_its_angle():
    # a crease end e at the origin, the chain along +x, a border edge (e, w) of length 0.93 at 19.3 deg
    # to the chain on one side, a short one at 100 deg on the other: only the narrow wedge asks for room
    from algorithms.creases import end_clearance

    th = np.radians(19.3)
    V = np.array([[0.0, 0, 0], [0.93 * np.cos(th), 0.93 * np.sin(th), 0], [-0.02, -0.1, 0], [0.5, -2, 0]])
    d = np.array([1.0, 0, 0])
    s = end_clearance(V, (0, 1, 3, 2), 0, d)
    # law of sines: the triangle (e, e + s d, w) has exactly 22 degrees at w
    assert np.isclose(_wedge_angle_at_w(V[0], s * d, V[1]), 22.0, atol=1e-9)
    assert 0.5 < s < 0.93
    # any chain vertex nearer leaves a smaller angle at w (the spacing's 0.31: 9.1 deg)
    assert _wedge_angle_at_w(V[0], 0.31 * d, V[1]) < 9.2
    # a wedge of 2 x 22 deg or more holds two faces: no clearance asked
    wide = np.radians(44.5)
    V2 = V.copy()
    V2[1] = [0.93 * np.cos(wide), 0.93 * np.sin(wide), 0]
    assert end_clearance(V2, (0, 1, 3, 2), 0, d) == 0.0


def test_spaced_chain_keeps_the_leads_and_the_even_spacing():
    from algorithms.bridge_graph import resample_chain
    from algorithms.creases import spaced_chain

    line = np.array([[0.0, 0, 0], [1.25, 0, 0]])
    even = resample_chain(line, 0.3125)
    np.testing.assert_array_equal(spaced_chain(line, 0.3125), even)  # no lead: resample_chain's points
    np.testing.assert_array_equal(spaced_chain(line, 0.3125, (0.3, 0.1)), even)  # leads within the step
    pts = spaced_chain(line, 0.3125, (0.64, 0.0))
    x = pts[:, 0]
    assert np.isclose(x[0], 0.64) and np.all(np.diff(x) > 0) and x[-1] < 1.25
    gaps = np.diff(np.r_[x, 1.25])
    assert np.allclose(gaps, gaps[0]) and 0.5 * 0.3125 <= gaps[0] <= 1.5 * 0.3125  # even again after the lead
    np.testing.assert_allclose(pts[:, 1:], 0.0)
    # both leads: the first and last points at them
    both = spaced_chain(line, 0.3125, (0.4, 0.5))[:, 0]
    assert np.isclose(both[0], 0.4) and np.isclose(both[-1], 0.75)
    # a lead leaving under half the spacing before a new chain vertex: no point (least=0), or one kept
    # a quarter of the curve from the end (the default, a chain between two border vertices)
    short = np.array([[0.0, 0, 0], [0.744, 0, 0]])
    assert len(spaced_chain(short, 0.3125, (0.0, 0.685), least=0)) == 0
    one = spaced_chain(short, 0.3125, (0.0, 0.685))
    assert len(one) == 1 and np.isclose(one[0, 0], 0.25 * 0.744)


def test_surface_touched_by_a_chain_through_an_input_vertex():
    from algorithms.creases import Surface

    V = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0], [1, -1, 0]])
    F = np.array([[0, 1, 3], [1, 2, 3], [0, 4, 1], [1, 4, 2]])
    s = Surface(V, F)
    p0, p1 = np.array([0.0, 0, 0]), np.array([2.0, 0, 0])
    assert s.touched_by(p0, np.array([[0.5, 0, 0], [1.5, 0, 0]]), p1, 1e-3)  # along the edges, through vertex 1
    assert not s.touched_by(p0, np.array([[1.0, 0.0, 0.5]]), p1, 1e-3)  # over the vertex, 0.5 above it
    assert not s.touched_by(V[0], np.zeros((0, 3)), V[3], 1e-3)  # its own ends do not count
    assert not s.crossed_by(p0, np.array([[0.5, 0, 0], [1.5, 0, 0]]), p1, 1e-3, 0.1)  # on edges: no face's inside


def _noisy_rim_cylinder(sections: int, noise: float, seed: int = 0):
    """A closed cylinder (radius 1, height 1, ``sections`` sides) whose top-rim points sit off the
    circle radially by up to ``noise`` (of the radius), with a notch of three side faces and their
    cap faces cut out at the rim: (vertices, faces, the notch's border vertices on the rim)."""
    cyl = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=sections)
    V = np.asarray(cyl.vertices, dtype=np.float64).copy()
    F = np.asarray(cyl.faces, dtype=np.int64)
    top = np.flatnonzero((np.abs(V[:, 2] - 0.5) < 1e-9) & (np.hypot(V[:, 0], V[:, 1]) > 0.5))
    rng = np.random.default_rng(seed)
    V[top, :2] *= (1.0 + rng.uniform(-noise, noise, len(top)))[:, None]
    cen = V[F].mean(axis=1)
    ang = np.arctan2(cen[:, 1], cen[:, 0])
    notch = (np.abs(ang) < 2.5 * 2 * np.pi / sections) & (cen[:, 2] > -0.2)
    return V, F[~notch], top


def test_a_fine_noisy_rim_gives_its_ends_the_rim_s_circle(monkeypatch):
    """A 256-gon rim, 1.4 degrees an edge, points off the circle by up to 1e-3 of the radius (as the
    mushroom's stem rim of bench/sweep.py): the circle through the last three vertices of the crease
    reads the noise (here radii 0.30 and 0.26 for 1); the circle fitted to the crease's longer
    stretch (creases.LONG_FIT) is the rim's, to a percent."""
    import algorithms.creases as cr

    V, F, top = _noisy_rim_cylinder(256, 1e-3)

    def radii():
        ends = crease_ends(V, F, 40.0)
        return [c.radius for v in top for c in ends.circles.get(int(v), []) if c is not None]

    got = radii()
    assert len(got) == 2 and all(abs(r - 1.0) < 0.01 for r in got), got  # the notch's two ends
    monkeypatch.setattr(cr, "LONG_FIT", 10**6)  # three points only, as before
    got = radii()
    assert len(got) == 2 and all(abs(r - 1.0) > 0.5 for r in got), got


def test_fit_circle_recovers_a_tilted_circle_and_refuses_a_line():
    from algorithms.creases import fit_circle

    rng = np.random.default_rng(2)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    e1 = np.cross(axis, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    centre, r = np.array([0.3, -1.2, 2.0]), 0.7
    t = np.linspace(0.2, 1.1, 9)  # an arc of 52 degrees
    p = centre + r * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * e2)
    c = fit_circle(p)
    assert np.allclose(c.center, centre, atol=1e-9) and abs(c.radius - r) < 1e-9
    assert abs(abs(float(c.axis @ axis)) - 1.0) < 1e-12
    assert fit_circle(np.outer(np.linspace(0, 1, 7), [1.0, 2.0, 3.0])) is None  # collinear


def test_a_curved_end_walks_on_over_notches_of_the_border_along_its_rim(monkeypatch):
    """A hole border that zigzags along a rim (every other border vertex on the rim's circle, the
    ones between 0.1 inside it): the end moves along the border to the last vertex on the circle,
    20 degrees round, and leaves along the circle's tangent there. Stepping only to the next
    border vertex (as before), it stays where it is: the next vertex is off the circle."""
    import algorithms.creases as cr
    from algorithms.creases import CreaseEnds

    ang = np.radians(np.arange(0, 22, 2.0))  # 0, 2, ..., 20 degrees: on the rim at even steps
    r = np.where(np.arange(len(ang)) % 2 == 0, 1.0, 0.9)
    rim = np.c_[r * np.cos(ang), r * np.sin(ang), np.zeros(len(ang))]
    # the hole's far side, then the crease's other end (off the polygon)
    V = np.vstack([rim, [[0.3, 0.2, 0.0], [0.3, -0.1, 0.0], [1.0, -0.1, 0.0]]])
    polygon = tuple(range(len(V) - 1))
    circle = Circle(np.zeros(3), 1.0, np.array([0.0, 0.0, 1.0]))

    def end():  # one curved end at vertex 0 (a new table each time: ``at`` records what it moved)
        return CreaseEnds({0: [np.array([0.0, 1.0, 0.0])]}, {0: [len(V) - 1]}, {0: [np.eye(3)[:2]]}, {0: [circle]})

    (k, d, _, c), = end().at(polygon, V)
    assert k == 10 and c is circle
    assert np.allclose(d, [-np.sin(ang[10]), np.cos(ang[10]), 0.0])
    monkeypatch.setattr(cr, "_on_circle", lambda p, c, tol=0.01: False)
    (k, d, _, c), = end().at(polygon, V)
    assert k == 0 and np.allclose(d, [0.0, 1.0, 0.0])


def test_a_rim_of_collinear_pieces_reads_as_its_circle_and_a_noisy_edge_stays_straight(monkeypatch):
    """trimesh's 48-gon cylinder subdivided twice (as the sweep's annulus, bench/sweep.py): each
    side of the rim is cut into four collinear pieces, so an end's last three points read straight
    (as before: no circle). The crease's longer stretch fits the rim's circle within creases.FIT
    and a line 10 times worse (creases.LINE): radius 0.997 (the pieces' midpoints lie inside the
    circle). A box edge whose points are off the line by up to 1e-3 fits a circle too (radii 7 and
    32 for an edge 2 long), and about as well as a line: it stays straight."""
    import algorithms.creases as cr
    from algorithms import cases as gen

    cyl = gen.subdivided(trimesh.creation.cylinder(radius=1.0, height=1.0, sections=48), 2)
    V, F = np.asarray(cyl.vertices), np.asarray(cyl.faces)
    cen = V[F].mean(axis=1)
    F = F[~((np.abs(np.arctan2(cen[:, 1], cen[:, 0])) < 0.2) & (cen[:, 2] > 0.2))]  # a notch at the top rim

    def radii(V, F):
        return [None if c is None else c.radius for cs in crease_ends(V, F, 40.0).circles.values() for c in cs]

    got = radii(V, F)
    assert len(got) == 2 and all(r is not None and abs(r - 1.0) < 0.005 for r in got), got
    box = gen.subdivided(trimesh.creation.box((2.0, 2.0, 1.0)), 5)
    B, G = np.asarray(box.vertices).copy(), np.asarray(box.faces)
    edge = (np.abs(B[:, 1] - 1.0) < 1e-9) & (np.abs(B[:, 2] - 0.5) < 1e-9)
    B[edge, 1:] += np.random.default_rng(0).uniform(-1e-3, 1e-3, (edge.sum(), 2))
    G = G[np.linalg.norm(B[G].mean(axis=1) - [0.0, 1.0, 0.5], axis=1) >= 0.1]  # a hole on the edge
    assert radii(B, G) == [None, None]
    monkeypatch.setattr(cr, "LINE", 0.0)
    assert all(r is not None and r > 5 for r in radii(B, G))
    monkeypatch.setattr(cr, "LINE", np.inf)  # as before
    assert radii(V, F) == [None, None]



def test_ends_of_a_noisy_fine_rim_that_read_straight_take_its_circle(monkeypatch):
    """The noisy 256-gon rim above over six noise seeds: an end's last three points bend by less
    than 3 degrees on some seeds and read straight (6 of the 12 ends, as before); read from the
    longer stretch too (creases.LINE), 11 of 12 ends get the rim's circle, each within 1 %."""
    import algorithms.creases as cr

    def radii():
        out = []
        for seed in range(6):
            V, F, top = _noisy_rim_cylinder(256, 1e-3, seed)
            out += [c and c.radius for v in top for c in crease_ends(V, F, 40.0).circles.get(int(v), [])]
        return out

    got = radii()
    assert len(got) == 12 and sum(r is not None and abs(r - 1.0) < 0.01 for r in got) == 11, got
    monkeypatch.setattr(cr, "LINE", np.inf)
    got = radii()
    assert sum(r is None for r in got) == 6, got

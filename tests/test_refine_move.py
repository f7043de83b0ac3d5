"""darning.refine: a free vertex squeezed against a ring vertex, where no collapse keeps the surface a
manifold, is moved to the best point of its star (refine._move_best, refine._collapse_bad)."""

import sys

import numpy as np

import algorithms.darning  # noqa: F401  (the package re-exports a function named refine)

R = sys.modules["algorithms.darning.refine"]


def _hexagon(squeeze: float):
    """A regular hexagon ring (unit radius, z = 0), the centre vertex 6 moved ``squeeze`` of the way to
    ring vertex 0: its star's smallest angle is tiny."""
    ang = np.arange(6) * np.pi / 3
    ring = np.stack([np.cos(ang), np.sin(ang), np.zeros(6)], axis=1)
    p = np.vstack([ring, [[squeeze, 0.0, 0.0]]])
    star = np.array([[6, i, (i + 1) % 6] for i in range(6)], dtype=np.int64)
    return p, star


def test_move_best_finds_the_centre_of_a_regular_hexagon():
    p, star = _hexagon(0.95)
    before = R.corner_angles(p, star).min()
    assert np.degrees(before) < 5
    assert R._move_best(p, star, 6, before)
    # the centre is the only point where all six faces are equilateral (60 degrees)
    assert np.linalg.norm(p[6]) < 0.02
    assert np.degrees(R.corner_angles(p, star).min()) > 59.0
    assert np.allclose(p[:6, 2], 0) and abs(p[6, 2]) < 1e-12  # in the star's plane


def test_move_best_refuses_when_nothing_is_better():
    p, star = _hexagon(0.0)
    q = p.copy()
    assert not R._move_best(p, star, 6, R.corner_angles(p, star).min())
    assert np.array_equal(p, q)


def test_collapse_bad_moves_when_every_collapse_breaks_the_link_condition():
    p, star = _hexagon(0.95)
    # fixed faces joining every second ring vertex: each ring vertex shares a third neighbour with
    # the centre, so no collapse of the centre keeps the surface a manifold
    fixed = np.array([[i, (i + 2) % 6, (i + 1) % 6] for i in range(6)], dtype=np.int64)
    free = np.r_[np.zeros(6, dtype=bool), True]
    before = np.degrees(R.corner_angles(p, star).min())
    f, done = R._collapse_bad(p, star, fixed, None, free, np.arange(6))
    assert done == 1
    assert np.array_equal(f, star)  # topology unchanged: the vertex moved
    assert before < 5 and np.degrees(R.corner_angles(p, f).min()) > 59.0


def test_a_folded_star_moves_along_the_plane_of_its_ring():
    """A star folded over a slit (its ring runs out from c and back beside itself, as at the copies of
    a pinched vertex): the faces' normals cancel, and what is left of their sum is no tangent plane.
    The move keeps to the least-squares plane of the ring (z = 0 up to 1e-3 here): on the torus cut of
    the sweep (torus:2:0, full mode) moving along the normals' sum put a vertex 1.3 % of the diagonal
    off the surface, which the angle refinement's points then followed (2.4 %)."""
    rng = np.random.default_rng(1)
    moved, worst = 0, 0.0
    for _ in range(200):
        a = np.sort(rng.uniform(0, 2 * np.pi, 3))
        out = np.c_[np.cos(a) * rng.uniform(0.5, 1, 3), np.sin(a) * rng.uniform(0.5, 1, 3), rng.normal(0, 1e-3, 3)]
        ring = np.vstack([out, out[::-1] + [0.05, 0.05, 0.0]])  # out, and back beside itself
        p = np.vstack([ring, [[0.0, 0.0, 0.0]]])
        star = np.array([[6, i, (i + 1) % 6] for i in range(6)], dtype=np.int64)
        t = p[star]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        assert (n @ n.sum(axis=0) < 0).any()  # folded
        if R._move_best(p, star, 6, R.corner_angles(p, star).min()):
            moved += 1
            worst = max(worst, abs(p[6, 2]))
    assert moved > 120  # 137; 160 before the moves were kept on the star's old faces (refine.ON_STAR)
    assert worst < 0.03  # along the normals' sum: 0.135


def _bent_star(rng):
    """A hexagonal star bent over a ridge (the ring's points at height -k |y|, k up to 1.5: a crease of
    up to 110 degrees), its centre pushed towards a ring vertex on one side: slivers."""
    ang = np.sort(rng.uniform(0, 2 * np.pi, 6))
    r = rng.uniform(0.6, 1.0, 6)
    k = rng.uniform(0.5, 1.5)
    ring = np.c_[r * np.cos(ang), r * np.sin(ang), -k * np.abs(r * np.sin(ang))]
    s = rng.uniform(0.7, 0.9)
    c = s * ring[0]
    c[2] = -k * abs(c[1])  # on the faces (the ridge's sides meet at y = 0)
    p = np.vstack([ring, c])
    return p, np.array([[6, i, (i + 1) % 6] for i in range(6)], dtype=np.int64)


def test_a_move_over_a_bent_star_lands_on_its_old_faces(monkeypatch):
    """The grid search runs in the plane of the star's normals' sum; over a bent star that plane
    leaves the faces. The point found is brought to the nearest point of the old faces (refine.ON_STAR)
    and kept only if the angles there still beat the old ones: the vertex stays on the surface its
    star spans (mushroom:5:0 of bench/sweep.py: points 0.10 into the cap before)."""
    from algorithms.metrics import point_to_surface

    rng = np.random.default_rng(3)
    stars = [_bent_star(rng) for _ in range(100)]
    off = {}
    for on_star in (True, False):
        monkeypatch.setattr(R, "ON_STAR", on_star)
        moved, worst = 0, 0.0
        for p0, star in stars:
            p = p0.copy()
            before = R.corner_angles(p, star).min()
            if R._move_best(p, star, 6, before):
                moved += 1
                assert R.corner_angles(p, star).min() > before
                worst = max(worst, float(point_to_surface(p[6:], p0, star)[0]))
        off[on_star] = (moved, worst)
    assert off[True][0] > 60 and off[True][1] < 1e-9, off  # on the old faces, to rounding
    assert off[False][1] > 0.05, off  # the plane's point itself: off the faces


def test_a_vertex_of_a_fixed_face_never_moves_whatever_movable_says():
    """refine_angles with every vertex named movable: the hole's border vertices (vertices of the fixed
    faces) stay where they are, the patch's own move (repair handed an input vertex over once, when a
    copy merged into it: bench/sweep.py annulus 12:1; its input face was lost)."""
    from test_refine_kernels import jittered_patch

    p, fixed, f, n = jittered_patch(0)
    q = R.refine_angles(p, f, fixed, movable=np.arange(len(p)))
    border = np.unique(fixed)
    assert np.array_equal(q.vertices[border], p[border])
    inner = np.setdiff1d(np.arange(n, len(p)), border)
    assert np.any(q.vertices[inner] != p[inner])  # the patch's vertices did move


def _cap_square():
    """A square patch (corners 0-3, border edges held by fixed faces outside) with three free vertices
    on one line across its middle, x (4), z (5) and y (6), z between the others: the face (x, z, y)
    has no area (a cap, 180 degrees at z), as where the convex clamp pressed a fill's vertices onto
    the line where two face planes meet (darning/convex.py)."""
    p = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [0.5, 1, 0], [1, 1, 0], [1.5, 1, 0],
                  [1, -1, 0], [3, 1, 0], [1, 3, 0], [-1, 1, 0]], dtype=float)
    A, B, C, D, x, z, y = range(7)
    patch = np.array([[A, B, z], [z, x, A], [y, z, B], [x, z, y], [x, y, C], [x, C, D], [A, x, D], [B, C, y]])
    fixed = np.array([[B, A, 7], [C, B, 8], [D, C, 9], [A, D, 10]])
    free = np.zeros(len(p), dtype=bool)
    free[[x, z, y]] = True
    return p, patch, fixed, free


def test_collapse_bad_removes_a_cap_of_no_area():
    """A face of no area (three vertices on one line) goes with a collapse of one of its vertices,
    and nothing folds."""
    p, patch, fixed, free = _cap_square()
    ang = np.degrees(R.corner_angles(p, patch).min(axis=1))
    assert ang[3] < 1e-6 and (np.delete(ang, 3) > 18).all()
    f, done = R._collapse_bad(p, patch, fixed, None, free, np.array([3]))
    assert done >= 1 and len(f) < len(patch)  # collapses (here x and y both onto z: four faces of 45 deg)
    assert np.degrees(R.corner_angles(p, f).min()) > 18
    t = p[f]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    assert (n[:, 2] > 0).all()  # nothing folded


def test_collapse_bad_leaves_a_pillow_vertex_alone():
    """A free vertex c whose star is two faces over the same three vertices (a pillow, left by the
    fill of a tiny hole): collapsing c onto either neighbour would remove its whole star, with no
    face left to judge. featuretype:42:0 of bench/sweep.py (full mode) raised a ValueError there
    (the smallest angle of no faces); now such a vertex is not collapsed (it may be moved)."""
    p = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0.02, 0], [0.5, 1, 0]])
    pillow = np.array([[2, 0, 1], [2, 1, 0]], dtype=np.int64)  # vertex 2, a sliver of 2 degrees
    fixed = np.array([[0, 3, 1]], dtype=np.int64)
    free = np.array([False, False, True, False])
    f, _ = R._collapse_bad(p, pillow, fixed, None, free, np.arange(2))
    assert np.array_equal(np.sort(f, axis=1), np.sort(pillow, axis=1))  # both faces there, vertex 2 kept

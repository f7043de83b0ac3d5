"""The finishing passes after Stage III: edge flips (flips.py) and smoothing on the surface (smooth.py)."""

import numpy as np
import pytest

from algorithms.hybrid import surfaces as S
from algorithms.hybrid.border import CURVE
from algorithms.hybrid.cdt import Triangulation
from algorithms.hybrid.flips import flip_pass
from algorithms.hybrid.model import HybridModel
from algorithms.hybrid.smooth import _min_angles, smooth
from algorithms.metrics import min_angles


def plane(stretch=0.0):
    """z = 0, x = u + stretch·u³ (a non-uniform parameterisation of the plane), y = v."""
    s = S.from_functions(lambda u, v: u + stretch * u ** 3, lambda u, v: v, lambda u, v: 0 * u, (-3.0, 3.0, -3.0, 3.0))
    return Triangulation(HybridModel("plane", s))


def build(tri, uv, faces):
    for p in uv:
        tri.add_vertex(tuple(p))
    # neighbours by shared edges (neighbour k is across the edge opposite vertex k)
    where = {}
    for t, f in enumerate(faces):
        tri._new(*f, -1, -1, -1)
        for k in range(3):
            where[(f[(k + 1) % 3], f[(k + 2) % 3])] = (t, k)
        for v in f:
            tri.vtri[v] = t
    for (a, b), (t, k) in where.items():
        if (b, a) in where:
            tri.tn[t][k] = where[(b, a)][0]
    return tri


def test_flip_replaces_the_long_diagonal_of_a_thin_quad():
    uv = [(0, 0), (2, 0), (1, -0.3), (1, 0.3)]  # p, q, r, s
    tri = build(plane(), uv, [[0, 2, 1], [1, 3, 0]])
    before = min_angles(np.array(tri.p3), tri.faces()).min()
    assert flip_pass(tri) == 1
    f = tri.faces()
    assert sorted(map(sorted, f.tolist())) == [[0, 2, 3], [1, 2, 3]]  # the diagonal r-s now
    assert min_angles(np.array(tri.p3), f).min() > before + 10
    # a border segment is never flipped
    tri2 = build(plane(), uv, [[0, 2, 1], [1, 3, 0]])
    tri2._add_segment(0, 1, CURVE)
    assert flip_pass(tri2) == 0


def test_smoothing_moves_towards_the_3d_mean_not_the_parameter_mean():
    st = 0.2
    tri = plane(st)
    # a regular hexagon in space around (1.5, 0); its parameters are not symmetric (x = u + 0.2 u³)
    ring3 = [(1.5 + np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 7)[:-1]]

    def inv(x):  # u with u + st u³ = x (Newton)
        u = x
        for _ in range(50):
            u -= (u + st * u ** 3 - x) / (1 + 3 * st * u * u)
        return u

    uv = [(inv(x), y) for x, y in ring3] + [(inv(1.75), 0.2)]  # the centre vertex off the middle
    faces = [[6, i, (i + 1) % 6] for i in range(6)]
    build(tri, uv, faces)
    for i in range(6):
        tri._add_segment(i, (i + 1) % 6, CURVE)
    ring_before = [tri.p3[i] for i in range(6)]
    before = min_angles(np.array(tri.p3), tri.faces()).min()
    moved = smooth(tri, passes=3)
    assert moved >= 1
    assert [tri.p3[i] for i in range(6)] == ring_before  # border vertices never move
    assert np.linalg.norm(np.array(tri.p3[6]) - [1.5, 0, 0]) < 1e-3
    assert min_angles(np.array(tri.p3), tri.faces()).min() > before
    # the parameter mean would have been a different point
    u_mean = np.mean([p[0] for p in uv[:6]])
    assert abs(u_mean + st * u_mean ** 3 - 1.5) > 0.02


def test_min_angles_helper_matches_metrics():
    rng = np.random.default_rng(1)
    V = rng.normal(size=(50, 3))
    F = np.array([[i, (i + 7) % 50, (i + 19) % 50] for i in range(50)])
    assert np.allclose(_min_angles(V[F]), min_angles(V, F), atol=1e-9)


def _off_centre_hexagon(centre):
    tri = plane()
    ring = [(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 7)[:-1]]
    build(tri, ring + [centre], [[6, i, (i + 1) % 6] for i in range(6)])
    for i in range(6):
        tri._add_segment(i, (i + 1) % 6, CURVE)
    return tri


def test_odt_smoothing_moves_to_the_area_weighted_mean_of_circumcentres():
    tri = _off_centre_hexagon((0.3, -0.2))
    P = np.array(tri.p3)
    # the ODT point of the fan, by hand: circumcentres of the six triangles weighted by their areas
    cc, w = [], []
    for i in range(6):
        A, B, C = P[6], P[i], P[(i + 1) % 6]
        M = 2 * np.array([B[:2] - A[:2], C[:2] - A[:2]])
        rhs = np.array([B[:2] @ B[:2] - A[:2] @ A[:2], C[:2] @ C[:2] - A[:2] @ A[:2]])
        cc.append(np.linalg.solve(M, rhs))
        (x1, y1), (x2, y2) = B[:2] - A[:2], C[:2] - A[:2]
        w.append(0.5 * abs(x1 * y2 - y1 * x2))
    odt = (np.array(w)[:, None] * np.array(cc)).sum(0) / sum(w)
    before = min_angles(P, tri.faces()).min()
    assert smooth(tri, passes=1, target="odt") == 1
    assert np.allclose(tri.p3[6][:2], odt, atol=1e-6)
    assert min_angles(np.array(tri.p3), tri.faces()).min() > before


def test_flips_keep_max_edge():
    # (smoothing's max_edge: tests/test_hybrid_coarsen.py, through the mesher)
    # a thin quad whose better diagonal is longer than max_edge is not flipped
    uv = [(0, 0), (2, 0), (1, -0.3), (1, 0.3)]
    tri = build(plane(), uv, [[0, 2, 1], [1, 3, 0]])
    assert flip_pass(tri, max_edge=0.5) == 0
    assert flip_pass(tri, max_edge=0.7) == 1
    with pytest.raises(ValueError, match="target"):
        smooth(tri, target="centroid")

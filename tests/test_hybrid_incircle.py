"""The 3D cylinder in-circle test (Fig. 3, (6)) against brute force."""

import numpy as np

from algorithms.hybrid.incircle import circumcentre_3d, incircle_2d, incircle_3d, min_angle_3d
from algorithms.metrics import min_angles


def random_rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q


def brute_circumcircle(A, B, C):
    # solve for the point of the plane equidistant from A, B, C
    n = np.cross(B - A, C - A)
    M = np.array([B - A, C - A, n])
    rhs = np.array([(B @ B - A @ A) / 2, (C @ C - A @ A) / 2, n @ A])
    O = np.linalg.solve(M, rhs)
    return O, np.linalg.norm(A - O)


def test_on_a_plane_equals_the_ordinary_test():
    rng = np.random.default_rng(3)
    agree = 0
    for _ in range(400):
        R = random_rotation(rng)
        shift = rng.normal(size=3)
        a2, b2, c2, p2 = (rng.random(2) for _ in range(4))
        if (b2[0] - a2[0]) * (c2[1] - a2[1]) - (b2[1] - a2[1]) * (c2[0] - a2[0]) < 0:
            b2, c2 = c2, b2
        A, B, C, P = (R @ np.r_[x, 0.0] + shift for x in (a2, b2, c2, p2))
        O, r = brute_circumcircle(A, B, C)
        brute = np.linalg.norm(P - O) < r
        if abs(np.linalg.norm(P - O) - r) < 1e-9:
            continue
        got = incircle_3d(tuple(A), tuple(B), tuple(C), tuple(P), 1e-12)
        assert got == brute == incircle_2d(tuple(a2), tuple(b2), tuple(c2), tuple(p2))
        assert np.allclose(circumcentre_3d(tuple(A), tuple(B), tuple(C)), O)
        agree += 1
    assert agree > 350


def test_cylinder_height():
    A, B, C = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    P = (0.4, 0.4, 0.05)  # inside the circumcircle, 0.05 above the plane
    assert incircle_3d(A, B, C, P, 0.1)
    assert not incircle_3d(A, B, C, P, 0.01)
    assert not incircle_3d(A, B, C, (2.0, 2.0, 0.0), 1.0)


def test_refiner_cached_circle_is_the_same_test():
    from algorithms.hybrid.cdt import Triangulation
    from algorithms.hybrid.model import HybridModel
    from algorithms.hybrid.refine import RefineParams, Refiner
    from algorithms.hybrid.surfaces import sphere

    tri = Triangulation(HybridModel("s", sphere(1.0, -1.0, 1.0)))
    rng = np.random.default_rng(1)
    for _ in range(3):
        tri.add_vertex(tuple(rng.random(2)))
    tri.tv.append([0, 1, 2])
    tri.tn.append([-1, -1, -1])
    tri.alive.append(True)
    ref = Refiner(tri, RefineParams())
    A, B, C = tri.p3
    for P in rng.normal(size=(200, 3)) * 0.5:
        assert ref.in_cylinder(0, tuple(P), height=False) == incircle_3d(A, B, C, tuple(P), np.inf)


def test_min_angle_3d_matches_metrics():
    rng = np.random.default_rng(2)
    T = rng.normal(size=(50, 3, 3))
    ref = min_angles(T.reshape(-1, 3), np.arange(150).reshape(-1, 3))
    got = [min_angle_3d(*map(tuple, t))[0] for t in T]
    assert np.allclose(got, ref)

"""APSS projection (algorithms/darning/apss.py) and its use in the repair on thin parts."""

import numpy as np
import pytest
from conftest import data_file

from algorithms.darning.apss import fit_spheres, project, project_to_spheres


def sphere_points(n=3000, radius=2.0, center=(1.0, 2.0, 3.0), max_z=0.7, seed=0):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = d[d[:, 2] < max_z]  # a spherical cap is missing: the points above are a hole
    return radius * d + np.asarray(center), d


def test_fit_recovers_the_sphere_exactly():
    p, n = sphere_points()
    x = np.zeros((1, 3))
    u0, u, u4 = fit_spheres(x, p[None], n[None], np.ones((1, len(p))))
    c = -u[0] / (2 * u4[0])
    r = np.sqrt(c @ c - u0[0] / u4[0])
    assert np.allclose(c, [1.0, 2.0, 3.0], atol=1e-9) and r == pytest.approx(2.0, abs=1e-9)


def test_points_in_a_spherical_hole_land_on_the_sphere():
    p, n = sphere_points()
    # starting points on the flat disk spanning the hole (what a membrane fill would give) and a
    # little inside the sphere: they are 0.1 .. 0.6 from the data
    rng = np.random.default_rng(1)
    a = rng.uniform(0, 2 * np.pi, 40)
    rr = rng.uniform(0.9, 1.4, 40)
    q = np.c_[rr * np.cos(a), rr * np.sin(a), np.full(40, 1.4)] + [1.0, 2.0, 3.0]
    out = project(q, p, n, spacing=0.2, near=(10.0, 20.0), disagree=None)  # trusted everywhere
    assert np.abs(np.linalg.norm(out - [1.0, 2.0, 3.0], axis=1) - 2.0).max() < 1e-9
    assert np.abs(np.linalg.norm(q - [1.0, 2.0, 3.0], axis=1) - 2.0).max() > 0.1  # they did move


def test_plane_and_trust_rules():
    rng = np.random.default_rng(2)
    p = np.c_[rng.uniform(-1, 1, (800, 2)), np.zeros(800)]
    n = np.tile([0.0, 0.0, 1.0], (800, 1))
    # (0, 0, 0.25): 2.5 spacings from the data, off by 2.5 spacings -> onto the plane; (0, 0, 0.02):
    # off by a fifth of a spacing -> kept (the fairing agrees within the tolerance); (0, 0, 0.9):
    # 9 spacings from the data -> kept (too far in to trust the fit)
    out = project(np.array([[0.0, 0.0, 0.25], [0.5, 0.2, 0.02], [0.0, 0.0, 0.9]]), p, n, spacing=0.1)
    assert abs(out[0, 2]) < 1e-9 and np.allclose(out[0, :2], 0.0)
    assert out[1, 2] == 0.02 and out[2, 2] == 0.9
    off = project_to_spheres(np.array([1.0]), np.array([[0.0, 0.0, 0.0]]), np.array([1.0]))
    assert np.isnan(off).all()  # x^2 + 1 = 0: no real sphere


def test_bunny_ear_rim_bite_follows_the_rim():
    """A ball bitten out of the bunny's ear rim (the ear is ~2 % of the diagonal thick): the plain
    fairing spans the bite nearly flat (measured: Hausdorff 1.71 % of the diagonal); with the APSS
    the fill follows the rim round (1.21 %)."""
    from algorithms.cases import cut, face_centroids
    from algorithms.io import load_raw
    from algorithms.mesh import Mesh
    from algorithms.metrics import distances, topology
    from algorithms.normalize import normalize
    from algorithms.repair import RepairParams, repair

    v, f = load_raw(data_file("bunny_closed.ply"))
    truth = Mesh(v, f)
    d = truth.bbox_diagonal()
    site = np.array([0.285, 0.535, 0.266])  # on the rim of the bunny's second ear
    c = cut(truth, np.linalg.norm(face_centroids(truth) - site, axis=1) < 0.03 * d, name="ear", description="")
    model = normalize(c.incomplete.vertices, c.incomplete.faces)
    h = {}
    for fit in ("none", "apss"):
        res = repair(model, RepairParams(fit=fit))
        t = topology(res.mesh.faces)
        assert t.watertight and t.components == 1 and t.genus == 0
        h[fit] = distances(res.mesh.vertices, res.mesh.faces, truth.vertices, truth.faces, samples=20000).hausdorff
    assert h["none"] > 0.015
    assert h["apss"] < 0.75 * h["none"] and h["apss"] < 0.0125


def _height_field(f, n=1500, seed=3, hole=0.35):
    """Points (with unit normals) of z = f(x, y) over [-1, 1]^2, a disk of radius ``hole`` missing."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-1, 1, (n, 2))
    xy = xy[np.linalg.norm(xy, axis=1) > hole]
    eps = 1e-6
    z = f(xy[:, 0], xy[:, 1])
    fx = (f(xy[:, 0] + eps, xy[:, 1]) - f(xy[:, 0] - eps, xy[:, 1])) / (2 * eps)
    fy = (f(xy[:, 0], xy[:, 1] + eps) - f(xy[:, 0], xy[:, 1] - eps)) / (2 * eps)
    nrm = np.c_[-fx, -fy, np.ones(len(xy))]
    return np.c_[xy, z], nrm / np.linalg.norm(nrm, axis=1, keepdims=True)


@pytest.mark.parametrize("f, expected", [
    (lambda x, y: 0.3 * (x * x - y * y), 1.0),  # a symmetric saddle
    (lambda x, y: 0.3 * (x * x - 0.5 * y * y), 0.5),  # k2 = -k1 / 2
    (lambda x, y: 0.3 * (x * x + y * y), 0.0),  # a cap
    (lambda x, y: 0.3 * x * x, 0.0),  # a cylinder
])
def test_saddle_measure_of_quadrics(f, expected):
    from algorithms.darning.apss import saddle_measure

    p, n = _height_field(f)
    x = np.zeros((1, 3))
    s = saddle_measure(x, p[None], n[None], np.ones((1, len(p))))
    assert s[0] == pytest.approx(expected, abs=0.02)  # the mean normal tilts a little off z: not exact


def test_a_saddle_hole_keeps_the_fill():
    """Over a hole in a saddle z = 0.3 (x^2 - y^2) no sphere fits: the faired fill (here the exact
    surface lifted 0.1 off it) would be moved towards a fitted sphere; the saddle test keeps it."""
    f = lambda x, y: 0.3 * (x * x - y * y)  # noqa: E731
    p, n = _height_field(f)
    rng = np.random.default_rng(4)
    a, r = rng.uniform(0, 2 * np.pi, 30), rng.uniform(0.0, 0.25, 30)
    q = np.c_[r * np.cos(a), r * np.sin(a), f(r * np.cos(a), r * np.sin(a)) + 0.1]
    moved = project(q, p, n, spacing=0.1, saddle=None)
    kept = project(q, p, n, spacing=0.1)
    assert np.abs(moved - q).max() > 0.05  # without the test the sphere pulls them
    assert np.array_equal(kept, q)

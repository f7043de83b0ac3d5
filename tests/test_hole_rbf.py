"""The RBF judge of holes where the APSS and the fairing disagree (algorithms/darning/hole_rbf.py)."""

import numpy as np
import pytest
from conftest import data_file

from algorithms.darning.hole_rbf import median_move, smooth_hole_fits


def test_median_move_brute_force():
    """Along the APSS move d = (0, 0, 1) from the faired point 0: the RBF beyond it keeps the whole
    move, short of it shortens the move to its height, the other way drops it."""
    faired = np.zeros((4, 3))
    apss = np.tile([0.0, 0.0, 1.0], (4, 1))
    rbf = np.array([[0.3, 0.0, 2.0], [0.3, 0.0, 0.4], [0.0, 0.2, -1.0], [0.0, 0.0, 1.0]])
    out, whole = median_move(faired, apss, rbf)
    assert np.allclose(out, [[0, 0, 1], [0, 0, 0.4], [0, 0, 0], [0, 0, 1]])
    assert whole.tolist() == [True, False, False, True]
    # every result is the median of the three scalars along d, brute force on random triples
    rng = np.random.default_rng(1)
    f, a, r = rng.normal(size=(3, 200, 3))
    out, _ = median_move(f, a, r)
    u = (a - f) / np.linalg.norm(a - f, axis=1, keepdims=True)
    s = np.median(np.c_[np.zeros(200), np.linalg.norm(a - f, axis=1), np.einsum("ij,ij->i", r - f, u)], axis=1)
    assert np.allclose(out, f + s[:, None] * u)


def _sphere_hole(doubt_move: float):
    """A unit icosphere with a cap cut out, its hole spanned by the flat disk through its loop
    (fill vertices inside the loop, on the plane), one fill vertex "moved by the APSS" by
    ``doubt_move`` edge lengths."""
    from algorithms.cases import icosphere
    from algorithms.topology import boundary_loops

    s = icosphere(4)
    v, f = s.vertices, s.faces
    cut = (v[f].mean(axis=1) @ np.array([0.0, 0.0, 1.0])) > 0.85
    used = np.unique(f[~cut])
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    v, f = v[used], remap[f[~cut]]
    loop = boundary_loops(f)[0]
    spacing = float(np.linalg.norm(v[f[:, 0]] - v[f[:, 1]], axis=1).mean())
    z = v[loop, 2].mean()
    rad = float(np.linalg.norm(v[loop, :2], axis=1).mean())
    g = np.stack(np.meshgrid(np.linspace(-rad, rad, 15), np.linspace(-rad, rad, 15)), -1).reshape(-1, 2)
    g = g[np.linalg.norm(g, axis=1) < 0.8 * rad]
    fill = np.c_[g, np.full(len(g), z)]
    V = np.vstack([v, fill])
    which = np.arange(len(v), len(V))
    moved = V.copy()
    moved[which[0], 2] += doubt_move * spacing
    return V, moved, f, len(v), V[: len(v)] / np.linalg.norm(V[: len(v)], axis=1, keepdims=True), loop, which, spacing


def test_smooth_hole_fit_recovers_the_sphere():
    """The RBF of the cap hole's rings: the flat fill projected onto it lies on the unit sphere
    within 0.4 % of the radius (measured 0.26 %: the input is a polyhedron; the flat fill sags by
    more than 5 %)."""
    V, moved, f, n, N, loop, which, spacing = _sphere_hole(2.0)
    fits = smooth_hole_fits(V, moved, f, n, N, [tuple(loop)], [which], spacing)
    assert len(fits) == 1
    rbf, w, reach = fits[0]
    assert np.array_equal(w, which)
    assert reach == pytest.approx(np.linalg.norm(V[loop] - V[loop].mean(axis=0), axis=1).max())
    assert np.abs(np.linalg.norm(V[which], axis=1) - 1).max() > 0.05
    on = rbf.project(V[which], reach=reach)
    assert np.abs(np.linalg.norm(on, axis=1) - 1).max() < 0.004


def test_smooth_hole_fits_only_doubted_holes():
    """A move of a quarter edge is not doubted (doubt = half an edge): no fit; one of 0.6 edge is;
    a loop across a thin part (opposite normals) is the thin-tip RBF's: no fit either."""
    V, moved, f, n, N, loop, which, spacing = _sphere_hole(0.25)
    assert smooth_hole_fits(V, moved, f, n, N, [tuple(loop)], [which], spacing) == []
    V, moved, f, n, N, loop, which, spacing = _sphere_hole(0.6)
    assert len(smooth_hole_fits(V, moved, f, n, N, [tuple(loop)], [which], spacing)) == 1
    assert smooth_hole_fits(V, moved, f, n, N, [tuple(loop)], [which], spacing, doubt=1.0) == []
    V, moved, f, n, N, loop, which, spacing = _sphere_hole(2.0)
    N2 = N.copy()
    N2[loop[0]] = -N2[loop[len(loop) // 2]]
    assert smooth_hole_fits(V, moved, f, n, N2, [tuple(loop)], [which], spacing) == []


def test_bunny_back_hole_is_not_dented(monkeypatch):
    """Two overlapping balls (radius 4 % of the diagonal) cut from the bunny's back (a hole of the
    unseen u-bunny-25 case): the APSS alone dented the fill by 1.15 % of the diagonal (its spheres,
    fitted to one side of the hole, extrapolated across it) where the fairing was within 0.4 %;
    with the median of fairing, APSS and the hole's RBF: 0.64 %."""
    import algorithms.darning.hole_rbf as hr
    from algorithms.cases import cut, face_centroids
    from algorithms.io import load_raw
    from algorithms.mesh import Mesh
    from algorithms.metrics import distances, topology
    from algorithms.normalize import normalize
    from algorithms.repair import RepairParams, repair

    v, f = load_raw(data_file("bunny_closed.ply"))
    truth = Mesh(v, f)
    d = truth.bbox_diagonal()
    fc = face_centroids(truth)
    balls = np.array([[0.222, 0.241, 0.462], [0.234, 0.293, 0.417]])  # bunny vertices (rounded)
    rm = (np.linalg.norm(fc[:, None] - balls[None], axis=2) < 0.04 * d).any(axis=1)
    c = cut(truth, rm, name="back", description="")
    model = normalize(c.incomplete.vertices, c.incomplete.faces)
    h = {}
    for judged in (False, True):
        if not judged:
            monkeypatch.setattr(hr, "smooth_hole_fits", lambda *a, **k: [])
        else:
            monkeypatch.undo()
        res = repair(model, RepairParams())
        t = topology(res.mesh.faces)
        assert t.watertight and t.components == 1 and t.genus == 0
        h[judged] = distances(res.mesh.vertices, res.mesh.faces, truth.vertices, truth.faces, samples=20000).hausdorff
    assert h[False] > 0.0105
    assert h[True] < 0.008


def test_a_hole_the_apss_moves_by_under_an_edge_is_judged_too():
    """The F-rep 'perturbed' object (bridgefield frep --demo perturbed --qlev 6, a shape no bench
    case is cut from) cut by three balls and a slab, light mode: the APSS moved one hole's fill by
    at most 0.86 edge, 1.65 % of the diagonal off the truth where the fairing was within 0.3 %.
    Judged from half an edge on, its median with the hole's RBF: 0.45 %."""
    from algorithms.cases import cut
    from algorithms.frep.objects import demo_object
    from algorithms.frep.pipeline import FrepParams, triangulate_object
    from algorithms.metrics import distances, topology
    from algorithms.normalize import normalize
    from algorithms.repair import repair
    from bench.cases import ball, slab

    truth = triangulate_object(demo_object("perturbed"), FrepParams(qlev=6)).mesh
    d = truth.bbox_diagonal()
    rm = np.zeros(truth.n_faces, dtype=bool)
    for centre, radius in (([-0.474164, 0.464217, 0.09932], 0.030535), ([-0.081036, -0.2594, 0.3484], 0.074319),
                           ([0.235369, 0.173556, -0.452173], 0.083202)):  # vertices of the object (rounded)
        rm |= ball(truth, np.array(centre), radius * d)
    n = np.array([0.183578, 0.331997, -0.39489])
    rm |= slab(truth, n, float(np.array([-0.628972, 0.32681, -0.002316]) @ n / np.linalg.norm(n)), 0.017719 * d)
    c = cut(truth, rm, name="perturbed-cut", description="", free_points=100, seed=1)
    res = repair(normalize(c.incomplete.vertices, c.incomplete.faces, extra_points=c.free_points))
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0
    h = distances(res.mesh.vertices, res.mesh.faces, truth.vertices, truth.faces, samples=20000).hausdorff
    assert h < 0.008

"""Fills that follow more than the fairing: the RBF implicit of a hole's rings (darning/implicit.py)
on a cut ellipsoid tip, and free points as samples of the missing surface (darning/samples.py)."""

from __future__ import annotations

import numpy as np

from algorithms import cases, metrics
from algorithms.boundary import vertex_normals
from algorithms.darning import apply_patch, darn, fair
from algorithms.darning.implicit import fit_rbf, folded, opposite_normals, refine_onto
from algorithms.darning.samples import free_samples, principal_normals, snap_to_samples
from algorithms.mesh import Mesh
from algorithms.topology import boundary_loops


def test_rbf_implicit_interpolates_and_reproduces_a_sphere():
    s = cases.icosphere(3)
    p = s.vertices
    rbf = fit_rbf(p, p, spacing=0.1)  # unit sphere: the normal is the position
    assert np.abs(rbf.value(p)).max() < 1e-8  # f = 0 at every surface point (interpolation)
    g = rbf.gradient(p)
    assert np.all(np.einsum("ij,ij->i", g, p) > 0)  # f grows outwards
    rng = np.random.default_rng(4)
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    for r in (0.85, 1.15):
        q = rbf.project(r * d)
        assert np.abs(np.linalg.norm(q, axis=1) - 1).max() < 0.01
    # a point whose Newton steps would move it farther than reach stays
    assert np.allclose(rbf.project(3.0 * d[:5], reach=0.5), 3.0 * d[:5])


def test_opposite_normals_tells_a_thin_tip_from_a_cap():
    a = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    tip = np.stack([np.cos(a), np.sin(a), np.full_like(a, 0.1)], axis=1)  # round a thin end: 169 deg apart
    cap = np.stack([0.5 * np.cos(a), 0.5 * np.sin(a), np.ones_like(a)], axis=1)  # a 27 degree cone
    assert opposite_normals(tip)
    assert not opposite_normals(cap)
    assert not opposite_normals(tip[:1])


def _ellipsoid_tip(angle: float):
    s = cases.icosphere(4)
    truth = Mesh(s.vertices * np.array([0.3, 0.12, 1.0]), s.faces)
    m = cases.cut(truth, cases.cap(s, [0, 0, 1], angle), name="tip", description="").incomplete
    return truth, m


def test_cut_ellipsoid_tip_rises_onto_the_implicit_of_its_rings():
    truth, m = _ellipsoid_tip(40.0)
    lp = boundary_loops(m.faces)[0]
    N = vertex_normals(m)
    assert opposite_normals(N[lp])  # the loop goes round a thin end: its sides face apart
    p = darn(m.vertices, m.faces, lp)
    V, F = apply_patch(m.vertices, m.faces, p)
    h_fair = metrics.distances(V, F, truth.vertices, truth.faces, samples=20000).hausdorff
    sel = np.zeros(m.n_vertices, dtype=bool)
    sel[lp] = True
    for _ in range(2):
        sel[m.faces[sel[m.faces].any(axis=1)].ravel()] = True
    pts = np.flatnonzero(sel)
    spacing = float(np.linalg.norm(m.vertices[np.roll(lp, -1)] - m.vertices[lp], axis=1).mean())
    rbf = fit_rbf(m.vertices[pts], N[pts], spacing=spacing, stride=2)
    nf = m.n_faces
    around = m.faces[np.isin(m.faces, F[nf:]).any(axis=1)]
    reach = float(np.linalg.norm(m.vertices[lp] - m.vertices[lp].mean(axis=0), axis=1).max())
    V2, pf, grown = refine_onto(rbf, V, F[nf:], around, np.arange(m.n_vertices, len(V)), spacing=spacing,
                                reach=reach)
    F2 = np.vstack([m.faces, pf])
    assert np.array_equal(V2[: m.n_vertices], m.vertices)  # the input stays
    assert len(grown) > len(V) - m.n_vertices  # the cap grew: the rounds refined it
    t = metrics.topology(F2)
    assert t.watertight and t.components == 1 and t.genus == 0 and t.oriented
    h = metrics.distances(V2, F2, truth.vertices, truth.faces, samples=20000).hausdorff
    # measured: fairing 8.4 % of the diagonal (the end comes back blunt), on the implicit 5.3 %
    assert h < 0.065
    assert h < 0.7 * h_fair
    assert metrics.min_angles(V2, pf).min() > 10.0


def test_principal_normals_of_a_plane():
    rng = np.random.default_rng(2)
    pts = np.c_[rng.uniform(-1, 1, (300, 2)), np.zeros(300)]
    n, ok = principal_normals(pts[:20], pts, k=10)
    assert ok.all()
    assert np.allclose(np.abs(n[:, 2]), 1.0, atol=1e-9)


def test_free_points_pull_a_fill_onto_a_sphere():
    s = cases.icosphere(4)
    case = cases.cut(s, cases.cap(s, [0.3, -0.4, 1.0], 50.0), name="cap", description="", free_points=80, seed=5)
    m, free = case.incomplete, np.asarray(case.free_points)
    assert len(free) == 80 and np.allclose(np.linalg.norm(free, axis=1), 1.0, atol=0.01)
    lp = boundary_loops(m.faces)[0]
    flat = darn(m.vertices, m.faces, lp, method="liepa-refine")  # the patch spans the hole flat
    V, F = apply_patch(m.vertices, m.faces, flat)
    new = np.arange(m.n_vertices, len(V))
    spacing = float(np.linalg.norm(m.vertices[np.roll(lp, -1)] - m.vertices[lp], axis=1).mean())
    # the samples with PRAF normals, signed like the fill (outwards, as the sphere's)
    sp, sn = free_samples(free, V, F, m.vertices, new, spacing=spacing)
    assert len(sp) > 60
    assert np.median(np.einsum("ij,ij->i", sn, sp / np.linalg.norm(sp, axis=1, keepdims=True))) > 0.95
    # the spec's U2 uniform fairing alone leaves the cap too flat; held at the samples it is not
    alone = fair(V, F, new, operator="U2", weights="uniform")
    pulled, held = snap_to_samples(V, F, new, free, spacing=spacing, n_fixed=m.n_vertices)
    assert len(held) > 20 and np.all(held >= m.n_vertices)
    assert np.array_equal(pulled[: m.n_vertices], V[: m.n_vertices])
    through = fair(pulled, F, np.setdiff1d(new, held), operator="U2", weights="uniform")

    def err(x):
        return float(np.abs(np.linalg.norm(x[new], axis=1) - 1).max())

    # measured (max radial error, unit sphere): flat 0.33, U2 alone 0.10, U2 through the free points 0.012
    assert err(V) > 0.25
    assert err(through) < 0.02
    assert err(through) < 0.2 * err(alone)
    # samples that agree with the fill (within half an edge along its normal) pull nothing
    _, none = snap_to_samples(through, F, new, free, spacing=spacing, n_fixed=m.n_vertices)
    assert len(none) == 0


def _thin_ellipsoid_rbf():
    s = cases.icosphere(3)
    axes = np.array([1.0, 0.06, 0.5])  # a thin plate with a rounded rim (|z| = 0.5 at x = 0)
    p = s.vertices * axes
    n = s.vertices / axes  # the gradient of x^2/a^2 + ...: the outward normal
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return fit_rbf(p, n, spacing=0.05, stride=3, offset=0.15)


def test_lines_along_a_fills_normals_reach_a_rim_the_gradient_misses():
    rbf = _thin_ellipsoid_rbf()
    # a fill that cut across the rim: points inside the plate, 0.1 short of the rim, its normal +z
    x = np.array([[0.0, 0.01, 0.4], [0.1, -0.01, 0.39], [-0.1, 0.005, 0.39]])
    rim = 0.5 * np.sqrt(1 - x[:, 0] ** 2)
    up = np.tile([0.0, 0.0, 1.0], (len(x), 1))
    lifted = rbf.project_along(x, up, reach=0.2)
    assert np.allclose(lifted[:, :2], x[:, :2])  # moved along the line only
    assert np.abs(lifted[:, 2] - rim).max() < 0.01  # onto the rim (analytic: z = 0.5 sqrt(1 - x^2))
    assert np.abs(rbf.value(lifted)).max() < 1e-6 * np.abs(rbf.value(x)).max() + 1e-9
    newton = rbf.project(x)  # down the gradient: to the nearer wall (|y| = 0.036), 0.1 short of the rim
    assert np.abs(newton[:, 1]).min() > 0.025 and (rim - newton[:, 2]).min() > 0.05
    # a line that meets no zero within reach stays; reach 0 moves nothing
    assert np.allclose(rbf.project_along(x, up, reach=0.05), x)
    assert np.allclose(rbf.project_along(x, up, reach=0.0), x)


def test_folded_faces_face_against_the_gradient():
    rbf = _thin_ellipsoid_rbf()
    s = cases.icosphere(2)
    V = s.vertices * np.array([1.0, 0.06, 0.5])
    assert not folded(rbf, V, s.faces).any()  # the surface itself, wound outward
    assert folded(rbf, V, s.faces[:, ::-1]).all()  # wound inward: every face against the gradient


def test_the_zero_in_a_bracket_takes_a_few_newton_steps_not_twenty_bisections(monkeypatch):
    """project_along brackets the zero on each line, then refines it: Newton steps along the line
    (the gradient comes with each value) reach what 20 bisections would in a handful of
    evaluations; the thin-part lifts of the repair evaluate the RBF at thousands of points each
    time (bunny cut 5:0: 2.5 s of its 5 s were these evaluations)."""
    from algorithms.darning import implicit

    rbf = _thin_ellipsoid_rbf()
    x = np.array([[0.0, 0.01, 0.4], [0.1, -0.01, 0.39], [-0.1, 0.005, 0.39]])
    up = np.tile([0.0, 0.0, 1.0], (len(x), 1))
    calls = []
    inner = implicit._rbf_eval

    def counted(q, c, w, a):
        calls.append(len(q))
        return inner(q, c, w, a)

    monkeypatch.setattr(implicit, "_rbf_eval", counted)
    lifted = rbf.project_along(x, up, reach=0.2)
    # 1 value at the start, 2 per step of h = 0.2 / 16 out to the rim 0.1 - 0.11 away (9 steps),
    # then the refinement: bisection alone would take 20 more
    assert len(calls) <= 1 + 2 * 9 + 6
    rim = 0.5 * np.sqrt(1 - x[:, 0] ** 2)
    assert np.abs(lifted[:, 2] - rim).max() < 0.01
    assert np.abs(rbf.value(lifted)).max() < 1e-6 * np.abs(rbf.value(x)).max() + 1e-9


def test_rbf_values_are_the_same_on_one_thread_and_on_many(monkeypatch):
    from algorithms.darning import implicit

    rng = np.random.default_rng(7)
    c, w, a = rng.random((300, 3)), rng.normal(size=300), rng.normal(size=4)
    q = rng.random((50, 3))
    serial = implicit._rbf_eval_serial(q, c, w, a)
    parallel = implicit._rbf_eval_parallel(q, c, w, a)
    for s, p in zip(serial, parallel, strict=True):
        assert np.array_equal(s, p)  # each point's sums in the same order: the same bits
    # the exact value at one point, summed in numpy
    d = q[3] - c
    r = np.linalg.norm(d, axis=1)
    assert abs(serial[0][3] - (a[0] + a[1:] @ q[3] + (w * r**3).sum())) < 1e-9
    assert np.allclose(serial[1][3], a[1:] + 3 * ((w * r)[:, None] * d).sum(axis=0))
    # a few points against a few centres run on one thread; many pairs in parallel
    calls = []
    monkeypatch.setattr(implicit, "_rbf_eval_serial", lambda *x: calls.append("serial") or serial)
    monkeypatch.setattr(implicit, "_rbf_eval_parallel", lambda *x: calls.append("parallel") or parallel)
    implicit._rbf_eval(q, c, w, a)
    monkeypatch.setattr(implicit, "PARALLEL_WORK", len(q) * len(c))
    implicit._rbf_eval(q, c, w, a)
    assert calls == ["serial", "parallel"]

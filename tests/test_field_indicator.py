"""The indicator field (eqs. 11-16): the tensor against a direct per-source loop, normals, Omega."""

import numpy as np
import pytest

from algorithms.boundary import loop_frames
from algorithms.bridges import attraction_index, field_context, local_maxima
from algorithms.cases import combine, disk
from algorithms.field.indicator import IndicatorField, Sources, direct_tensor, sources_from_frames, top_normal
from algorithms.mesh import Icadm
from algorithms.params import FieldParams


def random_sources(rng, m):
    p = rng.normal(size=(m, 3))
    tau = rng.normal(size=(m, 3))
    tau /= np.linalg.norm(tau, axis=1, keepdims=True)
    n = np.cross(tau, rng.normal(size=(m, 3)))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    b = np.cross(tau, n)
    z = np.zeros(m, dtype=np.int64)
    return Sources(p, tau, n, b, rng.uniform(0.5, 2, m), np.arange(m), z, z, z, np.arange(m), z + m)


@pytest.mark.parametrize("kernel", ["gauss", "cauchy"])
@pytest.mark.parametrize("mode", ["light", "full"])
def test_tensor_identity_against_direct_loop(kernel, mode):
    rng = np.random.default_rng(7)
    src = random_sources(rng, 40)
    p = FieldParams(q1_kernel=kernel, ki=0.8, mode=mode)
    field = IndicatorField(src, p, 1.3)
    x = rng.normal(size=(6, 3))
    ev = field.evaluate(x)
    for k in range(len(x)):
        H_ref = direct_tensor(x[k], src, p, 1.3)
        np.testing.assert_allclose(ev.H[k], H_ref, rtol=1e-6, atol=1e-9)
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        # f = H n equals the sum of the elementary forces d h Q(n) (11)
        from algorithms.field.quality import basic_task

        f = sum(src.charge[j] * basic_task(x[k], n, src.points[j], src.tangent[j], src.normal[j], p, 1.3)["d"]
                * basic_task(x[k], n, src.points[j], src.tangent[j], src.normal[j], p, 1.3)["Q"]
                for j in range(len(src)))
        np.testing.assert_allclose(ev.H[k] @ n, f, rtol=1e-6, atol=1e-9)


def test_normals_are_unit_perpendicular_and_maximal():
    rng = np.random.default_rng(11)
    H = rng.normal(size=(30, 3, 3))
    t = rng.normal(size=(30, 3))
    hint = rng.normal(size=(30, 3))
    n, ten = top_normal(H, t, hint)
    tu = t / np.linalg.norm(t, axis=1, keepdims=True)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)  # |n| = 1
    np.testing.assert_allclose((n * tu).sum(axis=1), 0.0, atol=1e-12)  # n . t = 0 (16)
    assert np.all((n * hint).sum(axis=1) >= 0)  # sign rule
    for k in range(30):  # maximal |H n| over the circle perpendicular to t (brute force)
        e1 = np.cross(tu[k], [1.0, 0, 0] if abs(tu[k, 0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(tu[k], e1)
        a = np.linspace(0, np.pi, 2000)
        cand = np.cos(a)[:, None] * e1 + np.sin(a)[:, None] * e2
        assert ten[k] >= np.linalg.norm(cand @ H[k].T, axis=1).max() - 1e-9


def test_normal_sign_continuity_along_a_path():
    m = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    src = sources_from_frames(loop_frames(m))
    src = src.subset(src.island == 1)
    field = IndicatorField(src, FieldParams(), 0.6)
    n_prev = np.array([0.0, 0, 1])
    for s in np.linspace(1.0, 1.55, 12):
        n, f, ten = field.sample_one(np.array([s, 0.05, 0.0]), np.array([1.0, 0, 0]), n_prev)
        assert n @ n_prev > 0.9 and ten > 0
        n_prev = n
    assert n_prev[2] > 0.99  # coplanar disks: the normal stays +z


def two_disks(flip=False):
    return Icadm(combine(disk((0, 0, 0)), disk((2.6, 0, 0), flip=flip)))


def test_attraction_index_peaks_at_the_facing_points():
    ctx = field_context(two_disks(), FieldParams(lc=0.6))
    omega, n = attraction_index(ctx)
    loops = {fr.island: w for fr, w in zip(ctx.frames, omega)}
    wa, wb = loops[0], loops[1]
    assert int(np.argmax(wa)) == 0 and int(np.argmax(wb)) == 32  # disk A at 0 deg, disk B at 180 deg
    assert wa[32] == 0.0 and wb[0] == 0.0  # far sides: the force points back into the island
    assert list(local_maxima(wa)) == [0]
    np.testing.assert_allclose(np.abs(n[:, 2]), 1.0, atol=1e-9)  # normals of coplanar disks: +-z
    assert np.all(n[:, 2] > 0)  # sign: n . n_O > 0


def test_local_maxima_on_a_closed_loop():
    w = np.array([3.0, 1, 2, 2, 0, 5, 4])
    assert list(local_maxima(w)) == [2, 5]  # index 0 (3 < 4 at index 6) is no max; plateau once
    assert list(local_maxima(w, floor=2.5)) == [5]


def test_chunking_does_not_change_the_field():
    rng = np.random.default_rng(5)
    src = random_sources(rng, 300)
    x = rng.normal(size=(100, 3))
    a = IndicatorField(src, FieldParams(), 1.0, chunk=7).evaluate(x).H
    b = IndicatorField(src, FieldParams(), 1.0).evaluate(x).H
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-14)


def test_single_point_closed_form_normal_matches_the_eigenvector():
    from algorithms.field.indicator import _normal_one

    rng = np.random.default_rng(13)
    for _ in range(50):
        H = rng.normal(size=(3, 3))
        t = rng.normal(size=3)
        hint = rng.normal(size=3)
        n, f = _normal_one(H, t, hint)
        n_ref, ten = top_normal(H[None], t[None], hint[None])
        assert abs(n @ n_ref[0]) == pytest.approx(1.0, abs=1e-9)
        assert n @ hint >= 0 and np.linalg.norm(f) == pytest.approx(ten[0], rel=1e-9)
        np.testing.assert_allclose(f, H @ n, atol=1e-12)
    # no tangent (a traced line whose target is its last point): unconstrained, as top_normal with
    # t = 0; the compiled tracer raised ZeroDivisionError there (featuretype cut by a slab)
    for _ in range(10):
        H, hint = rng.normal(size=(3, 3)), rng.normal(size=3)
        n, f = _normal_one(H, np.zeros(3), hint)
        n_ref, ten = top_normal(H[None], np.zeros((1, 3)), hint[None])
        np.testing.assert_allclose(n, n_ref[0], atol=1e-9)
        assert np.linalg.norm(f) == pytest.approx(np.linalg.svd(H, compute_uv=False)[0], rel=1e-9)


def test_full_mode_single_point_path_matches_evaluate():
    """sample_one in full mode (the tracing step's cached kernel call) gives H of evaluate."""
    from algorithms.cases import combine, disk
    from algorithms.field.free_points import free_points
    from algorithms.field.indicator import _normal_one
    from algorithms.field.shielding import mesh_bvh

    disks = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    src = sources_from_frames([f for f in loop_frames(disks) if f.island == 1])
    rng = np.random.default_rng(11)
    fp = free_points(np.column_stack([rng.uniform(1, 1.6, 30), rng.uniform(-0.5, 0.5, 30), np.zeros(30)]),
                     kt=0.5, rc=0.15)
    field = IndicatorField(src, FieldParams(mode="full", lc=0.6), 0.6, bvh=mesh_bvh(disks), free=fp)
    x = np.column_stack([rng.uniform(1.0, 1.6, 8), rng.uniform(-0.3, 0.3, 8), rng.uniform(-0.1, 0.1, 8)])
    t, hint = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    H = field.evaluate(x).H
    assert np.abs(H).max() > 0
    for k in range(len(x)):
        n, f, ten = field.sample_one(x[k], t, hint)
        n_ref, f_ref = _normal_one(H[k], t, hint)
        np.testing.assert_allclose(f, f_ref, rtol=1e-12, atol=1e-14)
        assert ten == pytest.approx(np.linalg.norm(f_ref))


@pytest.mark.parametrize("kernel", ["gauss", "cauchy"])
def test_per_point_lc_matches_one_call_per_lc_with_exclusions(kernel):
    """evaluate(x_lc=...) (light mode): each point with its own L_c gives exactly the H of a field
    built with that L_c, exclusions (own loop's window, own group) included; the direct loop agrees
    where nothing is excluded."""
    rng = np.random.default_rng(5)
    m = 60
    src = random_sources(rng, m)
    loop = np.repeat(np.arange(3), 20)
    pos = np.tile(np.arange(20), 3)
    src = Sources(src.points, src.tangent, src.normal, src.outward, src.charge, src.vertex, src.island,
                  loop.copy(), loop, pos, np.full(m, 20))
    p = FieldParams(q1_kernel=kernel, ki=0.8, mode="light")
    x = rng.normal(size=(9, 3))
    xl, xp, xw = np.array([0, 0, 1, 1, 2, 2, -1, -1, 0]), np.array([3, 19, 0, 10, 5, 6, 0, 0, 7]), np.full(9, 4)
    xw[6:8] = -1
    xg = np.full(9, -2)
    xg[8] = 1  # excludes the whole of loop 1 as its group
    lcs = np.array([0.4, 0.4, 0.9, 0.9, 1.7, 1.7, 0.6, 2.5, 1.1])
    # 18 points: the parallel kernel (16 or more points) against the serial one of a single point
    x, xg, xl, xp, xw = np.vstack([x, x + 0.1]), np.tile(xg, 2), np.tile(xl, 2), np.tile(xp, 2), np.tile(xw, 2)
    lcs = np.r_[lcs, lcs[::-1]]
    ev = IndicatorField(src, p, 1.0).evaluate(x, x_group=xg, x_loop=xl, x_pos=xp, x_window=xw, x_lc=lcs)
    for k in range(len(x)):
        one = IndicatorField(src, p, lcs[k]).evaluate(x[k:k + 1], x_group=xg[k:k + 1], x_loop=xl[k:k + 1],
                                                      x_pos=xp[k:k + 1], x_window=xw[k:k + 1])
        np.testing.assert_array_equal(ev.H[k], one.H[0])
        assert ev.nearest[k] == one.nearest[0]
    for k in (6, 7, 15, 16):  # no exclusion: the plain per-source loop (the Gaussian prunes below exp(-16))
        ref = direct_tensor(x[k], src, p, lcs[k])
        np.testing.assert_allclose(ev.H[k], ref, rtol=1e-6, atol=1e-6 * np.abs(ref).max())
    with pytest.raises(ValueError):
        IndicatorField(src, FieldParams(mode="full"), 1.0).evaluate(x, x_lc=lcs)

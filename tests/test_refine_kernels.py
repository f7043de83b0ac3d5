"""The compiled loops of the angle refinement (algorithms.darning.refine_kernels) against the numpy
functions of refine.py they replace, on small patches: the same moves, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from algorithms.cases import cap, cut, icosphere
from algorithms.darning import refine, triangulate
from algorithms.darning.refine import _smooth_bad, _unchangeable
from algorithms.darning.refine_kernels import corner_angles, smooth_bad, unchangeable
from algorithms.topology import boundary_loops


def jittered_patch(seed: int):
    """A hole cut from an icosphere, triangulated and refined, its new vertices jittered so that
    many patch faces have small angles. Returns (vertices, fixed faces, patch faces, n input)."""
    s = icosphere(3)
    inc = cut(s, cap(s, np.array([0.0, 0.0, 1.0]), 50.0), name="cap", description="a cap removed").incomplete
    fixed = np.asarray(inc.faces)
    vv = np.asarray(inc.vertices)
    lp = boundary_loops(fixed)[0]
    patch = lp[triangulate(vv[lp])]
    r = refine(vv, fixed, patch)
    p = r.vertices.copy()
    rng = np.random.default_rng(seed)
    n = len(vv)
    p[n:] += rng.normal(scale=0.04, size=(len(p) - n, 3))
    assert len(p) > n + 10
    return p, fixed, r.faces, n


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_smooth_bad_matches_the_numpy_loop(seed):
    p, fixed, f, n = jittered_patch(seed)
    free = np.zeros(len(p), dtype=bool)
    free[n:] = True
    bad = np.flatnonzero(corner_angles(p, f).min(axis=1) < np.radians(25))
    assert len(bad) > 5
    a, b = p.copy(), p.copy()
    ma = _smooth_bad(a, f, free, bad)
    mb = smooth_bad(b, f, free, bad)
    assert ma == mb > 0  # vertices moved, the same number
    np.testing.assert_array_equal(a, b)  # to the bit
    np.testing.assert_array_equal(a[:n], p[:n])  # only free vertices move
    assert corner_angles(b, f)[bad].min() > corner_angles(p, f)[bad].min()


@pytest.mark.parametrize("seed", [0, 3])
def test_unchangeable_matches_the_numpy_test(seed):
    p, fixed, f, n = jittered_patch(seed)
    rng = np.random.default_rng(seed)
    # a region of the patch (edges on its rim have one face), some locked edges inside
    sub = f[rng.random(len(f)) < 0.6]
    inner = np.stack([sub[:, 0], sub[:, 1]], axis=1)
    locked = inner[rng.choice(len(inner), size=5, replace=False)]
    for lk in (None, locked):
        ref = _unchangeable(sub, len(p), fixed, lk)
        got = unchangeable(sub, len(p), fixed, lk)
        np.testing.assert_array_equal(got, ref)
        assert ref.any() and not ref.all()
    # the locked edges count: more edges are unchangeable with them
    assert unchangeable(sub, len(p), fixed, locked).sum() > unchangeable(sub, len(p), fixed, None).sum()


def test_corner_angles_match_the_numpy_expression():
    from algorithms.darning.refine import _angle_at

    rng = np.random.default_rng(4)
    p = rng.normal(size=(500, 3))
    f = rng.integers(0, 500, size=(2000, 3))
    f[:5, 1] = f[:5, 0]  # degenerate corners: a zero edge
    ref = np.stack([_angle_at(p, f[:, k], f[:, (k + 1) % 3], f[:, (k + 2) % 3]) for k in range(3)], axis=1)
    got = corner_angles(p, f)
    np.testing.assert_allclose(got, ref, rtol=1e-14, atol=1e-15)
    # a triangle's angles sum to pi, a right triangle has its right angle where expected
    ok = np.all(f[:, [0, 1, 2]] != f[:, [1, 2, 0]], axis=1)
    np.testing.assert_allclose(got[ok].sum(axis=1), np.pi, rtol=1e-12)
    right = corner_angles(np.array([[0.0, 0, 0], [2.0, 0, 0], [0, 1.0, 0]]), np.array([[0, 1, 2]]))
    np.testing.assert_allclose(right[0], [np.pi / 2, np.arctan2(1, 2), np.arctan2(2, 1)], rtol=1e-14)

"""refine's compiled per-round tests (darning/split_kernels.py) against their numpy formulas."""

from __future__ import annotations

import numpy as np
from test_refine_kernels import _angle_at

from algorithms import cases
from algorithms.darning.split_kernels import centroid_splits, obtuse_edges
from algorithms.topology import halfedges


def _patch():
    s = cases.icosphere(2)
    rng = np.random.default_rng(5)
    p = np.asarray(s.vertices) + 0.05 * rng.standard_normal((len(s.vertices), 3))
    f = np.asarray(s.faces, dtype=np.int64)
    f = f[p[f].mean(axis=1)[:, 2] > 0.0]  # a cap: border edges have one face
    lv = 0.1 + 0.3 * rng.random(len(p))
    return p, f, lv


def test_centroid_splits_equal_the_spec_test():
    p, f, lv = _patch()
    for density in (1.0, np.sqrt(2.0), 3.0):
        split, vc, lc = centroid_splits(p, f, lv, density)
        t = p[f]
        want_vc = t.mean(axis=1)
        want_lc = lv[f].mean(axis=1)
        dist = density * np.linalg.norm(want_vc[:, None, :] - t, axis=2)
        want = np.all(dist > want_lc[:, None], axis=1) & np.all(dist > lv[f], axis=1)
        assert np.array_equal(split, want)
        if density == np.sqrt(2.0):
            assert 0 < want.sum() < len(f)  # some faces split, some not: the test decides
        np.testing.assert_array_equal(vc, want_vc)
        np.testing.assert_array_equal(lc, want_lc)


def test_obtuse_edges_equal_brute_force():
    p, f, lv = _patch()
    limit = np.radians(80.0)
    h1, h2, worst = obtuse_edges(p, f, lv, limit)
    he = halfedges(f)
    want = {}
    for h, (a, b) in enumerate(he):
        if a >= b:
            continue
        g = np.flatnonzero((he[:, 0] == b) & (he[:, 1] == a))
        if not len(g):
            continue  # a border edge
        g = int(g[0])
        c, d = f[h // 3, (h % 3 + 2) % 3], f[g // 3, (g % 3 + 2) % 3]
        w = max(_angle_at(p, np.array([c]), np.array([a]), np.array([b]))[0],
                _angle_at(p, np.array([d]), np.array([a]), np.array([b]))[0])
        if w > limit and np.linalg.norm(p[a] - p[b]) > 0.5 * (lv[a] + lv[b]) / 2:
            want[h] = (g, w)
    assert len(want) > 3
    assert list(h1) == sorted(want)
    assert [want[h][0] for h in h1] == list(h2)
    np.testing.assert_allclose(worst, [want[h][1] for h in h1], rtol=1e-15)

"""The compiled Delaunay flip passes (algorithms.darning.flips) against the vectorised numpy passes
they replace (kept here as the reference) and the Delaunay property on planar point sets."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from algorithms.darning import relax
from algorithms.topology import halfedges


def _angle_at(p, apex, a, b):
    u = p[a] - p[apex]
    w = p[b] - p[apex]
    return np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))


def _relax_reference(p, patch, fixed, locked=None, max_passes=200):
    """The former numpy implementation of refine.relax, pass by pass."""
    f = np.array(patch, dtype=np.int64, copy=True)
    nv = len(p)
    fixed_keys = np.unique(np.sort(halfedges(fixed), axis=1) @ np.array([nv, 1])) if len(fixed) else np.zeros(0, int)
    locked_keys = (np.unique(np.sort(np.asarray(locked), axis=1) @ np.array([nv, 1])) if locked is not None
                   else np.zeros(0, int))

    def has(sk, k):
        if not len(sk):
            return np.zeros(len(k), dtype=bool)
        i = np.minimum(np.searchsorted(sk, k), len(sk) - 1)
        return sk[i] == k

    total = 0
    active = np.ones(len(f), dtype=bool)
    for _ in range(max_passes):
        he = halfedges(f)
        key = he[:, 0] * nv + he[:, 1]
        twin_key = he[:, 1] * nv + he[:, 0]
        order = np.argsort(key)
        skey = key[order]
        pos = np.minimum(np.searchsorted(skey, twin_key), len(key) - 1)
        h1 = np.flatnonzero((skey[pos] == twin_key) & (he[:, 0] < he[:, 1]))
        h2 = order[pos[h1]]
        near = active[h1 // 3] | active[h2 // 3]
        h1, h2 = h1[near], h2[near]
        if not len(h1):
            break
        f1, f2 = h1 // 3, h2 // 3
        a, b = he[h1, 0], he[h1, 1]
        c = f[f1, (h1 % 3 + 2) % 3]
        d = f[f2, (h2 % 3 + 2) % 3]
        score = _angle_at(p, c, a, b) + _angle_at(p, d, a, b) - np.pi
        ok = (score > 1e-9) & (c != d) & ~has(locked_keys, np.minimum(a, b) * nv + np.maximum(a, b))
        ek = np.minimum(c, d) * nv + np.maximum(c, d)
        ok &= ~has(skey, c * nv + d) & ~has(skey, d * nv + c) & ~has(fixed_keys, ek)
        n_old = np.cross(p[b] - p[a], p[c] - p[a]) + np.cross(p[a] - p[b], p[d] - p[b])
        n1 = np.cross(p[a] - p[c], p[d] - p[c])
        n2 = np.cross(p[b] - p[d], p[c] - p[d])
        ok &= (np.einsum("ij,ij->i", n1, n_old) > 0) & (np.einsum("ij,ij->i", n2, n_old) > 0)
        cand = np.flatnonzero(ok)
        if not len(cand):
            break
        cand = cand[np.argsort(-score[cand], kind="stable")]
        fc = np.concatenate([f1[cand], f2[cand]])
        ec = np.concatenate([cand, cand])
        prio = np.concatenate([np.arange(len(cand)), np.arange(len(cand))])
        o = np.lexsort((prio, fc))
        first = np.ones(len(o), dtype=bool)
        first[1:] = fc[o][1:] != fc[o][:-1]
        chosen = np.full(len(f), -1)
        chosen[fc[o][first]] = ec[o][first]
        sel = cand[(chosen[f1[cand]] == cand) & (chosen[f2[cand]] == cand)]
        _, uniq = np.unique(ek[sel], return_index=True)
        sel = sel[np.sort(uniq)]
        f[f1[sel]] = np.stack([c[sel], a[sel], d[sel]], 1)
        f[f2[sel]] = np.stack([d[sel], b[sel], c[sel]], 1)
        total += len(sel)
        active[:] = False
        active[f1[sel]] = True
        active[f2[sel]] = True
    return f, total


def _fan_patch(seed, n=40):
    """A bumpy disk: a ring of n border points and random interior points, Delaunay-triangulated,
    then the interior points moved so that the connectivity is no longer Delaunay."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.c_[np.cos(t), np.sin(t)]
    inner = rng.uniform(-0.6, 0.6, (n, 2))
    xy = np.vstack([ring, inner])
    tri = Delaunay(xy).simplices
    z = 0.15 * np.sin(3 * xy[:, 0]) * np.cos(2 * xy[:, 1])
    p = np.c_[xy, z]
    # orient counter-clockwise seen from +z
    e1, e2 = xy[tri[:, 1]] - xy[tri[:, 0]], xy[tri[:, 2]] - xy[tri[:, 0]]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    tri[cw] = tri[cw][:, ::-1]
    # spoil it: move the interior points, so the connectivity is no longer Delaunay
    p[n:, :2] = rng.uniform(-0.6, 0.6, (n, 2)) * 0.5 + p[n:, :2] * 0.5
    return p, tri


@pytest.mark.parametrize("seed", range(6))
def test_flip_passes_match_the_vectorised_reference(seed):
    p, tri = _fan_patch(seed)
    fixed = tri[:5]
    patch = tri[5:]
    locked = patch[:3, :2] if seed % 2 else None
    ref_f, ref_n = _relax_reference(p, patch, fixed, locked)
    f, n = relax(p, patch, fixed, locked=locked)
    assert ref_n > 0  # the spoiled triangulation needs flips
    assert n == ref_n
    np.testing.assert_array_equal(f, ref_f)


def test_flip_passes_reach_delaunay_on_a_plane():
    rng = np.random.default_rng(3)
    xy = rng.uniform(0, 1, (60, 2))
    p = np.c_[xy, np.zeros(60)]
    d = Delaunay(xy)
    tri = d.simplices.copy()
    e1, e2 = xy[tri[:, 1]] - xy[tri[:, 0]], xy[tri[:, 2]] - xy[tri[:, 0]]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    tri[cw] = tri[cw][:, ::-1]
    bad = tri.copy()
    # move the points a little: the triangulation stays valid but is no longer Delaunay
    p2 = p.copy()
    p2[:, :2] += rng.normal(0, 0.01, (60, 2))
    f, n = relax(p2, bad, np.zeros((0, 3), dtype=np.int64))
    # no interior edge left with opposite angles summing to more than pi
    he = halfedges(f)
    key = {(int(a), int(b)): k for k, (a, b) in enumerate(he)}
    worst = -np.inf
    for (a, b), k in key.items():
        if (b, a) in key and a < b:
            c = f[k // 3, (k % 3 + 2) % 3]
            j = key[(b, a)]
            dd = f[j // 3, (j % 3 + 2) % 3]
            s = _angle_at(p2, np.array([c]), np.array([a]), np.array([b]))[0] + \
                _angle_at(p2, np.array([dd]), np.array([a]), np.array([b]))[0]
            worst = max(worst, s - np.pi)
    assert n > 0
    assert worst <= 1e-9
    assert len(f) == len(bad)  # flips keep the face count


def test_edge_keys_among_keeps_exactly_the_edges_between_patch_vertices():
    from algorithms.darning.flips import edge_keys_among

    rng = np.random.default_rng(2)
    nv = 40
    patch = rng.integers(0, 20, size=(15, 3))
    fixed = rng.integers(0, nv, size=(30, 3))
    pairs = rng.integers(0, nv, size=(12, 2))
    mine = set(np.unique(patch).tolist())
    for edges, faces in ((fixed, True), (pairs, False)):
        e = halfedges(edges) if faces else edges
        ref = sorted({min(a, b) * nv + max(a, b) for a, b in e.tolist() if a in mine and b in mine})
        got = edge_keys_among(patch, edges, nv, faces)
        assert got.tolist() == ref and 0 < len(ref) < len(e)


@pytest.mark.parametrize("seed", range(8))
def test_indexed_passes_match_passes_that_sort_every_time(seed):
    """flip_passes keeps its half-edge index up to date flip by flip instead of sorting the
    half-edges every pass: the same flips, face for face, on patches of a few hundred faces."""
    from algorithms.darning.flips import flip_passes

    p, tri = _fan_patch(100 + seed, n=120)
    keys = np.zeros(0, dtype=np.int64)
    f1, f2 = tri.copy(), tri.copy()
    n1 = flip_passes(p, f1, keys, keys, 200)
    n2 = flip_passes(p, f2, keys, keys, 200, False)
    assert n1 == n2 > 20
    np.testing.assert_array_equal(f1, f2)


def test_a_patch_with_a_repeated_directed_edge_flips_as_the_reference_does():
    """A face given twice repeats its three directed edges. The index holds one half-edge per edge
    (a flip would take an edge out of it that the other copy still has), so such a patch takes the
    passes that sort every time; they flip as the reference does, which finds the first copy."""
    p, tri = _fan_patch(7)
    patch = np.vstack([tri, tri[:1]])
    ref_f, ref_n = _relax_reference(p, patch, np.zeros((0, 3), dtype=np.int64))
    f, n = relax(p, patch, np.zeros((0, 3), dtype=np.int64))
    assert n == ref_n > 0
    np.testing.assert_array_equal(f, ref_f)

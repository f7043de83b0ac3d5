"""refine._polish, the last step of the angle refinement, on a hole like featuretype-hole's worst
corner: a row of 9 deg spikes (forced corners: two border edges) whose last tip T meets a long border
edge. The fan at T spans the angle between a 0.04 chord and the long edge; its faces need graded spokes
(refine._graded_points), which the off-centre insertions cannot place: every point they would insert
encroaches the long edge."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from algorithms.darning.liepa import triangulate
from algorithms.metrics import forced_faces

R = importlib.import_module("algorithms.darning.refine")


def _spiky_hole(turn: float, long: float, tip: float = 0.04, depth: float = 0.25, spikes: int = 3):
    """A planar hole (z = 0): ``spikes`` spikes along y = 0 (tips ``tip`` apart, valleys ``depth`` below),
    then from the last tip T a border edge of length ``long`` at ``turn`` deg, closed by three more edges.
    Returns (vertices, patch faces (the minimum-weight triangulation, then refine), fixed faces (one
    outside each border edge), border edges, index of T)."""
    pts = []
    for i in range(spikes):
        pts += [(i * tip, 0.0), (i * tip + tip / 2, -depth)]
    t = np.array([spikes * tip, 0.0])
    far = t + long * np.array([np.cos(np.radians(turn)), np.sin(np.radians(turn))])
    pts += [tuple(t), tuple(far), (-0.6, far[1]), (-0.6, -0.1)]
    v = np.c_[np.array(pts), np.zeros(len(pts))]
    n = len(v)
    patch = n - 1 - triangulate(v[::-1].copy())  # the loop in the surrounding surface's direction
    fixed = []
    for i in range(n):
        a, b = i, (i + 1) % n
        d = v[b] - v[a]
        v = np.vstack([v, (v[a] + v[b]) / 2 + np.array([d[1], -d[0], 0.0])])
        fixed.append((b, a, len(v) - 1))
    fixed = np.array(fixed)
    ref = R.refine(v, fixed, patch)
    border = np.c_[np.arange(n), (np.arange(n) + 1) % n]
    return ref.vertices, ref.faces, fixed, border, 2 * spikes


def _unforced_min(q, border):
    a = np.degrees(R.corner_angles(q.vertices, q.faces))
    return a[~forced_faces(q.vertices, q.faces, border)].min()


@pytest.mark.parametrize("turn, long", [(110.0, 0.41), (120.0, 0.3)])
def test_graded_fan_at_a_spike_tip(monkeypatch, turn, long):
    v, patch, fixed, border, tip = _spiky_hole(turn, long)
    q = R.refine_angles(v, patch, fixed)
    with monkeypatch.context() as m:
        m.setattr(R, "_polish", lambda p, f, *a, **k: (p, f, 0))
        plain = R.refine_angles(v, patch, fixed)
    assert _unforced_min(plain, border) < 14.0  # measured 13.1 and 7.1
    assert _unforced_min(q, border) >= 15.0  # measured 16.8 and 16.6
    # still the same planar hole: every face facing +z, every border edge in one face, the spikes kept
    p, f = q.vertices, q.faces
    assert np.allclose(p[np.unique(f), 2], 0.0)
    assert (np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])[:, 2] > 0).all()
    keys = {tuple(e) for e in np.sort(np.c_[f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]].reshape(-1, 2), axis=1).tolist()}
    assert all(tuple(sorted(e)) in keys for e in border.tolist())
    assert forced_faces(p, f, border).sum() == 3
    # the fan at the tip T now has more faces than the two it had
    assert (f == tip).any(axis=1).sum() > (plain.faces == tip).any(axis=1).sum()


def test_graded_points_split_the_fan_evenly():
    # a fan of one face at vertex 0: spokes of length 1 (along x) and 0.1 at 60 deg
    p = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.1 * np.cos(np.pi / 3), 0.1 * np.sin(np.pi / 3), 0]])
    f = np.array([[0, 1, 2]])
    x = R._graded_points(p, f, np.zeros(1, dtype=bool), 0, 3)
    np.testing.assert_allclose(np.linalg.norm(x, axis=1), 0.1 ** (np.arange(1, 4) / 4), rtol=1e-12)
    np.testing.assert_allclose(np.degrees(np.arctan2(x[:, 1], x[:, 0])), [15.0, 30.0, 45.0], atol=1e-9)
    # a vertex inside a closed fan has no first spoke: no graded points
    p2 = np.vstack([p, [[-1.0, -1.0, 0]]])
    f2 = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1]])
    assert R._graded_points(p2, f2, np.zeros(3, dtype=bool), 0, 2) is None


def _grid(n: int = 7):
    """A flat n x n grid of points (z = 0), two faces per cell, wound to face +z."""
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    v = np.c_[x.ravel(), y.ravel(), np.zeros(n * n)]
    f = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, i * n + j + 1, (i + 1) * n + j + 1, (i + 1) * n + j
            f += [(a, b, c), (a, c, d)]
    return v, np.array(f)


def test_folded_pairs_on_a_pushed_through_vertex():
    v, f = _grid()
    assert len(R._folded_pairs(v, f)) == 0
    w = v.copy()
    w[24, :2] += (1.6, 0.3)  # the centre vertex pushed over its right neighbour: faces turn over
    pairs = R._folded_pairs(w, f)
    assert len(pairs) > 0
    assert (f[pairs] == 24).any(axis=(1, 2)).all()  # every fold has a face at the pushed vertex
    # a crease that is meant to be sharp is not a fold when it is listed
    edges = np.unique(np.sort(np.c_[f[pairs[:, 0]], f[pairs[:, 0]][:, [1, 2, 0]]].reshape(-1, 2), axis=1), axis=0)
    assert len(R._folded_pairs(w, f, ignore=edges)) == 0


def test_no_points_into_a_crumple(monkeypatch):
    """refine_angles inserts no point into the faces of a crumple (bunny-islands' ear tip: points there
    multiplied into clusters of tiny faces); its moves and collapses unfold it instead."""
    v, f = _grid()
    v = v.copy()
    v[24, :2] += (1.6, 0.3)
    inner = (v[f][:, :, 0].min(axis=1) >= 1) & (v[f][:, :, 0].max(axis=1) <= 5) & \
        (v[f][:, :, 1].min(axis=1) >= 1) & (v[f][:, :, 1].max(axis=1) <= 5)
    inner |= (f == 24).any(axis=1)
    patch, fixed = f[inner], f[~inner]
    folded = len(R._folded_pairs(v, patch))
    seen = []
    orig = R._insert

    def spy(p, ff, fx, lk, bad, corner, nv):
        seen.append(ff[bad].copy())
        return orig(p, ff, fx, lk, bad, corner, nv)

    monkeypatch.setattr(R, "_insert", spy)
    q = R.refine_angles(v, patch, fixed, movable=np.array([24]))
    assert folded > 0 and seen
    assert not any((s == 24).any() for s in seen)  # never a face at the crumpled vertex
    assert len(R._folded_pairs(q.vertices, q.faces)) <= folded

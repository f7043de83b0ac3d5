"""The compiled loops of the angle refinement (algorithms.darning.refine_kernels) against the numpy
functions of refine.py they replace, on small patches: the same moves, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from algorithms.cases import cap, cut, icosphere
from algorithms.darning import refine, triangulate
from algorithms.darning.refine_kernels import corner_angles, grid_search, smooth_bad, star_scores, stars, unchangeable
from algorithms.topology import boundary_loops, halfedges


# the numpy versions the compiled kernels replaced, kept here as their references
def _tri_angles(t: np.ndarray) -> np.ndarray:
    """(..., 3) corner angles (radians) of triangles given as (..., 3, 3) corner positions."""
    out = np.empty(t.shape[:-1])
    for k in range(3):
        u = t[..., (k + 1) % 3, :] - t[..., k, :]
        w = t[..., (k + 2) % 3, :] - t[..., k, :]
        c0 = u[..., 1] * w[..., 2] - u[..., 2] * w[..., 1]
        c1 = u[..., 2] * w[..., 0] - u[..., 0] * w[..., 2]
        c2 = u[..., 0] * w[..., 1] - u[..., 1] * w[..., 0]
        out[..., k] = np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2), (u * w).sum(axis=-1))
    return out


def _unchangeable(f, nv, fixed, locked):
    """(M, 3) whether edge k of each patch face (f[:, k] -> f[:, k+1]) can neither split nor flip: a
    hole border edge (an edge of a fixed face), a locked edge, or an edge with one patch face."""
    keys = []
    if len(fixed):
        keys.append(np.sort(halfedges(fixed), axis=1) @ np.array([nv, 1]))
    if locked is not None:
        keys.append(np.sort(locked, axis=1) @ np.array([nv, 1]))
    a, b = f, np.roll(f, -1, axis=1)
    out = np.isin(np.minimum(a, b) * nv + np.maximum(a, b), np.unique(np.concatenate(keys))) if keys \
        else np.zeros(f.shape, dtype=bool)
    he = np.sort(halfedges(f), axis=1) @ np.array([nv, 1])
    _, inv, cnt = np.unique(he, return_inverse=True, return_counts=True)
    return out | (cnt[inv] < 2).reshape(-1, 3)


def _smooth_bad(p, f, free, bad, *, tries=3, gain=0.1 * np.pi / 180):
    """Move the free vertices of the bad faces, in place, to raise the smallest angle of their faces
    (smart Laplacian smoothing, in the vertex's tangent plane): candidates are the umbrella step
    towards the centroid of the neighbours (fair.tangential_relax's step) and, for the face of the
    star with the smallest angle, the apex of the equilateral triangle on its edge opposite the
    vertex, each at full, half and quarter length; the best candidate that raises the star's
    smallest angle by more than ``gain`` (radians) without folding a face is kept. A free vertex near
    a fixed edge, where no point may be inserted (the encroachment rule of :func:`_insert`), can
    only be moved. Returns the number of moves kept."""
    cand, order, start, stop = stars(f, free, bad)
    if not len(cand):
        return 0
    kept = 0
    steps = np.array([1.0, 0.5, 0.25])
    for _ in range(tries):  # sequential: each vertex moves against its neighbours' current positions
        moved = 0
        for c, s0, s1 in zip(cand, start, stop):
            star = f[order[s0:s1] // 3]
            nb = star[star != c]  # each neighbour twice (in two faces of the star) unless on its rim
            t = p[star]
            nrm = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]).sum(axis=0)
            nn = np.linalg.norm(nrm)
            if not len(nb) or nn == 0:
                continue
            nrm /= nn
            ang = _tri_angles(t)
            before = ang.min()
            # the face with the smallest angle: the equilateral apex on its edge opposite c
            w = star[int(np.argmin(ang.min(axis=1)))]
            kc = int(np.flatnonzero(w == c)[0])
            ea, eb = p[w[(kc + 1) % 3]], p[w[(kc + 2) % 3]]
            e = eb - ea
            side = np.cross(nrm, e)
            side /= max(float(np.linalg.norm(side)), 1e-300)
            if side @ (p[c] - (ea + eb) / 2) < 0:
                side = -side
            apex = (ea + eb) / 2 + np.sqrt(3) / 2 * float(np.linalg.norm(e)) * side
            dl = np.stack([p[nb].mean(axis=0) - p[c], apex - p[c]])
            dl -= (dl @ nrm)[:, None] * nrm
            trial = p[c] + (steps[None, :, None] * dl[:, None, :]).reshape(-1, 3)  # (6, 3)
            tt = np.broadcast_to(t, (len(trial),) + t.shape).copy()
            tt[:, star == c] = trial[:, None, :]
            n2 = np.cross(tt[:, :, 1] - tt[:, :, 0], tt[:, :, 2] - tt[:, :, 0])
            score = _tri_angles(tt).min(axis=(1, 2))
            score[((n2 @ nrm) <= 0).any(axis=1)] = -1.0  # a fold
            b = int(np.argmax(score))
            if score[b] > before + gain:
                p[c] = trial[b]
                moved += 1
        kept += moved
        if not moved:
            break
    return kept



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
    # the same moves; positions equal to rounding (not to the bit: numpy's own sums, e.g. in norm
    # and mean, change their order between releases: numpy 2.4.6 / numba 0.68.1 differ by 3e-17)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
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


def _angle_at(p, apex, a, b):
    """Angle at ``apex`` in the triangles (apex, a, b), radians: the numpy reference of the compiled
    angles (refine.py's before its loops were compiled)."""
    u = p[a] - p[apex]
    w = p[b] - p[apex]
    return np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))


def test_corner_angles_match_the_numpy_expression():
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


def _star_scores(t, at, x, n_old):
    """refine._move_best's grid score in numpy (its code before the kernel): the star with the
    corners ``at`` at each candidate, its smallest angle, -1 where a face's normal turns over."""
    tt = np.broadcast_to(t, (len(x),) + t.shape).copy()
    tt[:, at] = np.repeat(x, at.sum(), axis=0).reshape(len(x), -1, 3)
    n2 = np.cross(tt[:, :, 1] - tt[:, :, 0], tt[:, :, 2] - tt[:, :, 0])
    score = _tri_angles(tt).min(axis=(1, 2))
    score[(np.einsum("kij,ij->ki", n2, n_old) <= 0).any(axis=1)] = -1.0
    return score


def test_star_scores_match_the_numpy_grid_score():
    # a hexagonal fan around vertex 6 (at the origin), tilted out of the plane a little
    ang = np.arange(6) * np.pi / 3
    p = np.c_[np.cos(ang), np.sin(ang), 0.1 * np.sin(2 * ang)]
    p = np.vstack([p, [0.0, 0.0, 0.0]])
    star = np.array([[6, i, (i + 1) % 6] for i in range(6)])
    t = p[star]
    n_old = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    g = np.linspace(-1.5, 1.5, 31)
    a, b = np.meshgrid(g, g)
    x = np.c_[a.ravel(), b.ravel(), np.zeros(a.size)]
    ref = _star_scores(t, star == 6, x, n_old)
    got = star_scores(t, star == 6, x, n_old)
    np.testing.assert_allclose(got, ref, rtol=1e-14, atol=1e-15)
    # outside the hexagon some face turns over; at the centre nothing does, and the score is the
    # smallest angle of the (nearly regular) fan
    assert (got == -1).sum() > 100 and (got > 0).sum() > 100
    centre = int(np.argmin(np.linalg.norm(x, axis=1)))
    assert got[centre] == pytest.approx(corner_angles(p, star).min(), rel=1e-12)


def _grid_search(t, at, centre, half, e1, e2, n_old, threshold, grid, levels):
    """refine._move_best's search loop in numpy (its code before the kernel)."""
    best_m, best_x = threshold, None
    g = np.linspace(-1.0, 1.0, grid)
    for _ in range(levels):
        a, b = np.meshgrid(g * half, g * half)
        x = centre + a.reshape(-1, 1) * e1 + b.reshape(-1, 1) * e2
        score = _star_scores(t, at, x, n_old)
        k = int(np.argmax(score))
        if score[k] > best_m:
            best_m, best_x = float(score[k]), x[k]
        if best_x is None:
            return np.full(3, np.nan)
        centre, half = best_x, half * 2.0 / (grid - 1) * 2
    return best_x


@pytest.mark.parametrize("grid", [11, 21])
def test_grid_search_matches_the_numpy_loop(grid):
    rng = np.random.default_rng(7)
    ang = np.sort(rng.uniform(0, 2 * np.pi, 7))
    r = rng.uniform(0.5, 1.5, 7)
    p = np.vstack([np.c_[r * np.cos(ang), r * np.sin(ang), 0.05 * rng.normal(size=7)], [0.6, 0.3, 0.0]])
    star = np.array([[7, i, (i + 1) % 7] for i in range(7)])
    t = p[star]
    n_old = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    e1, e2 = np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    before = corner_angles(p, star).min()
    ref = _grid_search(t, star == 7, p[7], 1.5, e1, e2, n_old, before, grid, 4)
    got = grid_search(t, star == 7, p[7], 1.5, e1, e2, n_old, before, grid, 4)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-15)
    assert not np.isnan(got).any()  # the off-centre vertex has a better place
    # nothing beats an impossible threshold: NaNs
    assert np.isnan(grid_search(t, star == 7, p[7], 1.5, e1, e2, n_old, np.pi, grid, 4)).all()

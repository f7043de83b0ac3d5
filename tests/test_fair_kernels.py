"""fair.py's compiled small-system path (darning/fair_kernels.py) against the sparse path it
replaces: the same fairing system (U1/U2/U3, uniform and cotangent weights, bare vertices), the
dense LU against LAPACK, and the compiled tangential relaxation against its numpy formula."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from algorithms import cases
from algorithms.darning.fair import ORDERS, cotan_laplacian, tangential_relax, uniform_laplacian
from algorithms.darning.fair_kernels import dense_solve, power_system

fair_mod = importlib.import_module("algorithms.darning.fair")


def _sphere_cap():
    """A noisy unit icosphere; free: the vertices of a cap, bare: a few fixed vertices beside it."""
    s = cases.icosphere(3)
    v = np.asarray(s.vertices) * (1 + 0.02 * np.random.default_rng(3).standard_normal((len(s.vertices), 1)))
    f = np.asarray(s.faces)
    free = np.flatnonzero(v[:, 2] > 0.6)
    ring = np.setdiff1d(np.unique(f[np.isin(f, free).any(axis=1)]), free)
    return v, f, free, ring[::3]


@pytest.mark.parametrize("operator", ["U1", "U2", "U3"])
@pytest.mark.parametrize("weights", ["uniform", "cotan"])
@pytest.mark.parametrize("with_bare", [False, True])
def test_dense_fairing_equals_sparse_fairing(monkeypatch, operator, weights, with_bare):
    v, f, free, bare = _sphere_cap()
    b = bare if with_bare else None
    moved = v.copy()
    moved[free] *= 0.8  # start away from the solution: the fairing must move them
    dense = fair_mod.fair(moved, f, free, operator=operator, weights=weights, bare=b)
    monkeypatch.setattr(fair_mod, "DENSE_MAX", -1)  # every system through the sparse path
    sparse = fair_mod.fair(moved, f, free, operator=operator, weights=weights, bare=b)
    assert np.abs(dense[free] - moved[free]).max() > 1e-3
    # the same system summed in another order: round-off times the condition number (cotan U3 on
    # this cap: about 1.5e4)
    np.testing.assert_allclose(dense, sparse, rtol=0, atol=1e-9 if operator == "U3" else 1e-10)


def test_power_system_rows_are_rows_of_the_matrix_power():
    v, f, free, _ = _sphere_cap()
    L = cotan_laplacian(v, f)
    order = np.resize(np.array([1, 2, 3], dtype=np.int64), len(free))
    A, rhs = power_system(L.indptr.astype(np.int64), L.indices.astype(np.int64), L.data, free, order, v)
    Ld = L.toarray()
    fixed = np.setdiff1d(np.arange(len(v)), free)
    for i, (r, k) in enumerate(zip(free, order)):
        row = np.linalg.matrix_power(Ld, int(k))[r]
        np.testing.assert_allclose(A[i], row[free], atol=1e-9 * np.abs(row).max())
        np.testing.assert_allclose(rhs[i], -(row[fixed] @ v[fixed]), atol=1e-9 * np.abs(row).max())


def test_dense_solve_matches_lapack_and_flags_singular():
    rng = np.random.default_rng(1)
    A = rng.standard_normal((40, 40))
    b = rng.standard_normal((40, 3))
    x, ok = dense_solve(A, b)
    assert ok
    np.testing.assert_allclose(x, np.linalg.solve(A, b), atol=1e-10)
    A[:, 7] = 0.0  # a zero column: exactly singular
    assert not dense_solve(A, b)[1]
    # one right-hand side and a symmetric indefinite matrix: the RBF fit's system (implicit.fit_rbf)
    S = rng.standard_normal((60, 60))
    S = S + S.T
    y = rng.standard_normal((60, 1))
    x, ok = dense_solve(S, y)
    assert ok and np.allclose(x, np.linalg.solve(S, y), atol=1e-9)
    assert not dense_solve(np.ones((3, 3)), np.ones((3, 1)))[1]


def test_free_vertex_without_faces_keeps_its_position(monkeypatch):
    """A free vertex no face uses has a zero row: it stays put, the others are faired as before."""
    v, f, free, _ = _sphere_cap()
    v2 = np.vstack([v, [[5.0, 5.0, 5.0]]])
    free2 = np.append(free, len(v))
    out = fair_mod.fair(v2, f, free2, operator="U3", weights="cotan")
    assert np.array_equal(out[-1], v2[-1])
    np.testing.assert_allclose(out[:-1], fair_mod.fair(v, f, free, operator="U3", weights="cotan"), atol=1e-12)
    monkeypatch.setattr(fair_mod, "DENSE_MAX", -1)
    np.testing.assert_allclose(out, fair_mod.fair(v2, f, free2, operator="U3", weights="cotan"), atol=1e-10)


def test_compiled_tangential_relax_equals_its_formula():
    v, f, free, _ = _sphere_cap()
    got = tangential_relax(v, f, free, iterations=4, step=0.5)
    ref = v.copy()
    L = uniform_laplacian(len(v), f)[free]
    for _ in range(4):
        t = ref[f]
        fn = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        n = np.zeros_like(ref)
        for k in range(3):
            np.add.at(n, f[:, k], fn)
        n = n[free] / np.linalg.norm(n[free], axis=1, keepdims=True)
        d = L @ ref
        d -= np.einsum("ij,ij->i", d, n)[:, None] * n
        ref[free] += 0.5 * d
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-13)
    keep = np.setdiff1d(np.arange(len(v)), free)
    assert np.array_equal(got[keep], v[keep])
    assert ORDERS["U3"] == 3


def test_laplacians_match_their_definitions():
    """uniform_laplacian and cotan_laplacian (compiled) against the formulas, built densely face by
    face on a noisy sphere with a zero-area face (three collinear points) and an unused vertex."""
    v, f, _, _ = _sphere_cap()
    m = len(v)
    v = np.vstack([v, [[2.0, 0, 0], [3.0, 0, 0], [4.0, 0, 0], [9.0, 9.0, 9.0]]])  # the last: unused, an empty row
    f = np.vstack([f, [[m, m + 1, m + 2]]])  # zero area: cotangents clipped, its rows zero (no area)
    n = len(v)
    A = np.zeros((n, n))
    for a, b, c in f:
        for x, y in ((a, b), (b, c), (c, a)):
            A[x, y] = A[y, x] = 1.0
    deg = A.sum(axis=1)
    U = np.where(deg[:, None] > 0, A / np.maximum(deg, 1)[:, None], 0.0) - np.diag((deg > 0).astype(float))
    np.testing.assert_allclose(uniform_laplacian(n, f).toarray(), U, atol=1e-15)
    t = v[f]
    dbl = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    floor = dbl.max() * 1e-12
    C = np.zeros((n, n))
    M = np.zeros(n)
    for i, tri in enumerate(f):
        for k in range(3):
            o, a, b = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
            cot = np.clip((v[a] - v[o]) @ (v[b] - v[o]) / max(dbl[i], floor), -1e3, 1e3)
            C[a, b] += cot / 2
            C[b, a] += cot / 2
            M[o] += dbl[i] / 6
    inv = np.where(M > 0, 1 / np.where(M > 0, M, 1), 0.0)
    ref = inv[:, None] * (C - np.diag(C.sum(axis=1)))
    got = cotan_laplacian(v, f).toarray()
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    assert np.all(np.isfinite(got)) and not got[-1].any()

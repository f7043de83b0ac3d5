"""Fairing a patch: U1 = 0 (membrane) or U2 = 0 (thin plate) with uniform weights
(spec/frep.md §4 "Matching the curvature").

    U1(p) = -p + (1/n(p)) sum_i p_i                        (umbrella operator)
    U2(p) = -U1(p) + (1/n(p)) sum_i U1(p_i)                (as written in frep.md §4)

With L = D^-1 A - I (uniform weights, A the vertex adjacency), U1 = L x and, since the spec's
U2 = -U1 + mean U1(p_i) = (D^-1 A - I) U1, U2 = L (L x). For the free (patch-interior) vertices we
solve U = 0 with every other vertex fixed:

    (L^k)[free, free] x_free = -(L^k)[free, fixed] x_fixed,     k = 1 (U1) or 2 (U2),

one sparse solve for the three coordinates (scipy.sparse.linalg.splu); a system of at most
``DENSE_MAX`` free vertices (a hole's patch) is assembled compiled and solved with dense LU instead
(fair_kernels.py: the same system; per-call overhead dominated the sparse route there). The rows of L^2 at a free
vertex reach two rings out, so the hole border and one ring of fixed vertices beyond it act as
the boundary condition (positions and tangents). The spec's iteration "solve, move, repeat"
converges to this same fixed point; with uniform weights it is reached in one solve.

**(choice)** ``weights="cotan"``: the same system with the area-normalised cotangent Laplacian
L = M^-1 (C - diag C1) (M the barycentric vertex areas), whose weights are computed from the
current positions and refreshed ``iterations`` times. Uniform weights pull the vertices towards
the patch's combinatorial centre, which on a curved hole of irregular density leaves the patch
flatter than the surroundings; cotangent weights follow the geometry (measured on a sphere cap
of 35 degrees: max radial error 0.042 uniform, 0.010 cotangent).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu
from scipy.spatial import cKDTree

from .fair_kernels import cotan_csr, dense_solve, power_system, relax_steps, ring_distance, uniform_csr

ORDERS = {"umbrella": 1, "U1": 1, "bilaplacian": 2, "U2": 2, "trilaplacian": 3, "U3": 3}
WEIGHTINGS = ("uniform", "cotan")
# **(choice)** fair(): a cotangent solve that moved a free region by more than this many reaches
# and lies as far from the uniform solve is replaced by the uniform one if that one stays within
# as many reaches. Measured: the bench's repairs are unchanged (quick-repair, all 14 cases, both
# modes); the capsule strip moved 4.2 reaches, the cylinder band 1.26
# (tests/test_repair_sliver_shapes.py)
AGREE = 1.0
# **(choice)** systems of at most this many free vertices (a hole's patch) are assembled compiled and
# solved with dense LU (_fair_solve_dense); larger ones (a whole mesh's new vertices) stay sparse
DENSE_MAX = 800


def _faces(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    return np.ascontiguousarray(np.asarray(faces, dtype=np.int64).reshape(-1, 3))


def _csr(arrays: tuple[NDArray, NDArray, NDArray], n: int) -> sp.csr_matrix:
    indptr, indices, data = arrays
    return sp.csr_matrix((data, indices, indptr), shape=(n, n))


def uniform_laplacian(n_vertices: int, faces: NDArray[np.int64]) -> sp.csr_matrix:
    """L = D^-1 A - I over the vertices (1/deg off the diagonal, -1 on it, columns sorted); rows of
    vertices without edges are zero. Built compiled (fair_kernels.uniform_csr)."""
    return _csr(uniform_csr(_faces(faces), int(n_vertices)), int(n_vertices))


def cotan_laplacian(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> sp.csr_matrix:
    """L = M^-1 (C - diag(C 1)): C_ab = (cot alpha + cot beta) / 2 over the faces at edge ab,
    M the barycentric area (a third of the incident faces' area). Cotangents are clipped to
    [-1e3, 1e3] and areas floored so that degenerate input triangles cannot break the system.
    Built compiled (fair_kernels.cotan_csr; columns sorted, exact zeros left out, as sparse
    products would leave them)."""
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    return _csr(cotan_csr(v, _faces(faces)), len(v))


def fair(vertices: NDArray[np.float64], faces: NDArray[np.int64], free: NDArray[np.int64], *,
         operator: str = "U2", weights: str = "uniform", iterations: int = 2,
         bare: NDArray[np.int64] | None = None) -> NDArray[np.float64]:
    """New positions (V, 3) with the ``free`` vertices moved so that U1 = 0 or U2 = 0 there.

    faces must hold every face around the free vertices and, for U2, every face around their
    neighbours (the hole border's outer ring), e.g. the whole mesh.
    operator: "U2"/"bilaplacian" (default), "U1"/"umbrella", or "U3"/"trilaplacian" (L^3 x = 0:
        continues the curvature of the surroundings; needs two fixed rings around the free vertices;
        measured on the big-hole demo, a 62 degree cap of the unit sphere filled after repair:
        Hausdorff 3.0 % of the diagonal with U2, 0.35 % with U3, both cotangent weights).
    weights: "uniform" (the spec's) or "cotan" (recomputed ``iterations`` times).
    With cotangent weights, a region the system throws far is checked against the uniform solve
    (``_cotan_guard``).
    bare: fixed vertices whose own neighbourhood is missing (e.g. a bridge chain whose other side
        is not filled yet): L at such a vertex is meaningless, so a free vertex j rings from one
        solves L^min(k, j) x = 0 (next to a bare vertex U1 = 0: positions only as the boundary
        condition there).
    """
    if operator not in ORDERS:
        raise ValueError(f"operator must be one of {sorted(ORDERS)}, got {operator!r}")
    if weights not in WEIGHTINGS:
        raise ValueError(f"weights must be one of {WEIGHTINGS}, got {weights!r}")
    if iterations < 1:
        raise ValueError(f"iterations must be >= 1, got {iterations}")
    v = np.asarray(vertices, dtype=np.float64)
    free = np.unique(np.asarray(free, dtype=np.int64))
    out = v.copy()
    if not len(free):
        return out
    is_free = np.zeros(len(v), dtype=bool)
    is_free[free] = True
    fixed = np.flatnonzero(~is_free)
    f = _faces(faces)
    for _ in range(1 if weights == "uniform" else iterations):  # sequential: cotan weights follow the positions
        if weights == "uniform":
            out[free] = _fair_solve(uniform_csr(f, len(v)), out, free, fixed, ORDERS[operator], bare)
            continue
        try:
            out[free] = _fair_solve(cotan_csr(out, f), out, free, fixed, ORDERS[operator], bare, strict=True)
        except RuntimeError:  # singular cotangent system (degenerate triangles): uniform weights
            out[free] = _fair_solve(uniform_csr(f, len(v)), out, free, fixed, ORDERS[operator], bare)
    if weights == "cotan":
        out = _cotan_guard(v, out, f, free, fixed, ORDERS[operator], bare)
    return out


def _cotan_guard(v: NDArray[np.float64], out: NDArray[np.float64], f: NDArray[np.int64], free: NDArray[np.int64],
                 fixed: NDArray[np.int64], k: int, bare: NDArray[np.int64] | None) -> NDArray[np.float64]:
    """An ill-conditioned cotangent system that did not raise (slivers around the free vertices):
    a free region (``free_regions``) whose vertices it moved by more than AGREE reaches, and where
    it strays from the spec's uniform weights by as much, takes the uniform solution, if that one
    stays within as many reaches. The regions are independent systems (the fixed vertices separate
    them). A region both solves throw far is a near-singular system the callers' own fallbacks
    handle (plausible(), lower orders), better than uniform U3 (featuretype cut by a slab: 2.9 ->
    10 % otherwise)."""
    moved = np.linalg.norm(out[free] - v[free], axis=1)
    dist = _rim_distance(v, free, f)
    if np.all(moved <= AGREE * dist):  # a region's reach is at least each of its vertices' distance
        return out
    label, reach = free_regions(v, free, f, dist=dist)
    lim = AGREE * reach[label]
    uni = _fair_solve(uniform_csr(f, len(v)), v.copy(), free, fixed, k, bare)
    off = ~(moved <= lim) & ~(np.linalg.norm(out[free] - uni, axis=1) <= lim)  # NaN counts as off
    bad = np.zeros(len(reach), dtype=bool)
    np.logical_or.at(bad, label, off)
    calm = np.ones(len(reach), dtype=bool)
    np.logical_and.at(calm, label, np.linalg.norm(uni - v[free], axis=1) <= lim)
    take = (bad & calm)[label]
    out[free[take]] = uni[take]
    return out


def _rim_distance(before: NDArray[np.float64], free: NDArray[np.int64],
                 faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """(len(free),) each free vertex's distance to the nearest fixed vertex of a face touching a
    free vertex (inf if there is none)."""
    is_free = np.zeros(len(before), dtype=bool)
    is_free[free] = True
    f = faces[is_free[faces].any(axis=1)]
    rim = np.unique(f[~is_free[f]])
    if not len(rim):
        return np.full(len(free), np.inf)
    return cKDTree(before[rim]).query(before[free])[0]


def free_regions(before: NDArray[np.float64], free: NDArray[np.int64], faces: NDArray[np.int64], *,
                 dist: NDArray[np.float64] | None = None) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """(label per free vertex, reach per label). A free region is a connected set of free vertices
    (one hole's fill, or fills joined by free bridge chains); its reach is the largest distance of
    its vertices to the nearest fixed vertex of a face touching a free vertex (``_rim_distance``,
    given as ``dist`` when already known; inf if there is none)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    free = np.asarray(free, dtype=np.int64)
    is_free = np.zeros(len(before), dtype=bool)
    is_free[free] = True
    f = faces[is_free[faces].any(axis=1)]
    pos = np.full(len(before), -1, dtype=np.int64)
    pos[free] = np.arange(len(free))
    a, b = f.ravel(), np.roll(f, -1, axis=1).ravel()
    both = is_free[a] & is_free[b]
    g = coo_matrix((np.ones(int(both.sum())), (pos[a[both]], pos[b[both]])), shape=(len(free),) * 2)
    label = connected_components(g, directed=False)[1] if len(free) else np.zeros(0, dtype=np.int64)
    reach = np.zeros(label.max(initial=-1) + 1)
    np.maximum.at(reach, label, _rim_distance(before, free, faces) if dist is None else dist)
    return label, reach


def _fair_solve(L: tuple[NDArray, NDArray, NDArray], out: NDArray[np.float64], free: NDArray[np.int64],
                fixed: NDArray[np.int64], k: int, bare: NDArray[np.int64] | None, *,
                strict: bool = False) -> NDArray[np.float64]:
    """Positions of the free vertices with L^k x = 0 there (lower powers near bare vertices). L: the
    Laplacian's CSR arrays (indptr, indices, data); at most DENSE_MAX free vertices take the dense path."""
    if len(free) <= DENSE_MAX:
        return _fair_solve_dense(L, out, free, k, bare, strict=strict)
    M = _csr(L, len(out))
    # the rows of L^j at the free vertices only: row f of L^j = (row f of L^(j-1)) L, the same sums
    # as the whole product's row, without the rows of every fixed vertex
    powers = [M[free]]
    for _ in range(k - 1):  # L^k: k = 3 also matches curvature across the border
        powers.append((powers[-1] @ M).tocsr())
    rows = powers[-1]
    if k > 1 and bare is not None and len(bare):
        # the row of L^j at f reads L at the vertices up to j-1 rings from f: a free vertex j
        # rings from a bare vertex solves L^min(k, j) = 0
        order = _bare_order(L, len(out), free, k, bare)
        if (order < k).any():
            rows = _mixed_rows(powers, order)
    rhs = -(rows[:, fixed] @ out[fixed])
    return _solve(rows[:, free].tocsr(), rhs, out[free], strict=strict)


def _fair_solve_dense(L: tuple[NDArray, NDArray, NDArray], out: NDArray[np.float64], free: NDArray[np.int64],
                      k: int, bare: NDArray[np.int64] | None, *, strict: bool = False) -> NDArray[np.float64]:
    """_fair_solve for a patch of at most DENSE_MAX free vertices: the same system, its rows built
    compiled (fair_kernels.power_system) from L's CSR arrays and solved with dense LU (no
    sparse-matrix call overhead)."""
    indptr, indices, data = L
    free = np.asarray(free, dtype=np.int64)
    order = np.full(len(free), k, dtype=np.int64)
    if k > 1 and bare is not None and len(bare):  # as in _fair_solve
        order = _bare_order(L, len(out), free, k, bare)
    A, rhs = power_system(indptr, indices, data, free, order, np.ascontiguousarray(out, dtype=np.float64))
    x0 = out[free]
    zero = np.abs(A).sum(axis=1) == 0
    if zero.any():  # a free vertex whose row vanished keeps its position (as in _solve)
        A[zero, zero] = 1.0
        rhs = np.where(zero[:, None], x0, rhs)
    x, ok = dense_solve(A, rhs)
    if ok and np.all(np.isfinite(x)):
        return x
    if strict:  # exactly singular
        raise RuntimeError("singular fairing system")
    eps = 1e-9 * float(np.abs(A).max())
    return dense_solve(A + eps * np.eye(len(A)), rhs + eps * x0)[0]


def _solve(A: sp.csr_matrix, rhs: NDArray[np.float64], x0: NDArray[np.float64], *,
           strict: bool = False) -> NDArray[np.float64]:
    """A x = rhs by sparse LU. A free vertex whose row vanished (all its faces degenerate) keeps its
    position; a system that is still singular (a free region with no path to a fixed vertex) is
    solved with a tiny diagonal shift towards the current positions (``strict``: raise instead)."""
    zero = np.asarray(abs(A).sum(axis=1)).ravel() == 0
    if zero.any():
        A = (A + sp.diags(zero.astype(np.float64))).tocsr()
        rhs = np.where(zero[:, None], x0, rhs)
    try:
        x = splu(A.tocsc()).solve(rhs)
        if not np.all(np.isfinite(x)):
            raise RuntimeError("non-finite solution")
        return x
    except RuntimeError:  # exactly singular
        if strict:
            raise
        eps = 1e-9 * float(abs(A).max())
        return splu((A + eps * sp.identity(A.shape[0])).tocsc()).solve(rhs + eps * x0)


def _bare_order(L: tuple[NDArray, NDArray, NDArray], n: int, free: NDArray[np.int64], k: int,
                bare: NDArray[np.int64]) -> NDArray[np.int64]:
    """(len(free),) min(k, rings from the nearest bare vertex) over the edges of L (CSR arrays;
    compiled BFS, fair_kernels.ring_distance)."""
    is_bare = np.zeros(n, dtype=bool)
    is_bare[np.asarray(bare, dtype=np.int64)] = True
    return ring_distance(*L, is_bare, int(k))[free]


def _mixed_rows(powers: list[sp.csr_matrix], order: NDArray[np.int64]) -> sp.csr_matrix:
    """Row i of powers[order[i] - 1] for each i (powers[j - 1]: the rows of L^j at the free vertices)."""
    parts, where = [], []
    for j in range(1, len(powers) + 1):
        sel = np.flatnonzero(order == j)
        if len(sel):
            parts.append(powers[j - 1][sel])
            where.append(sel)
    stacked = sp.vstack(parts).tocsr()
    pos = np.concatenate(where)
    inv = np.empty_like(pos)
    inv[pos] = np.arange(len(pos))
    return stacked[inv]


def tangential_relax(vertices: NDArray[np.float64], faces: NDArray[np.int64], free: NDArray[np.int64], *,
                     iterations: int = 5, step: float = 0.5) -> NDArray[np.float64]:
    """Even out the free vertices along the surface: each moves ``step`` of the way towards the
    centroid of its neighbours, with the component along its normal removed (a tangential umbrella
    step; the shape changes only to second order). Used after cotangent fairing, which places
    vertices accurately on the surface but unevenly."""
    v = np.array(vertices, dtype=np.float64, copy=True)
    f = np.asarray(faces, dtype=np.int64)
    free = np.unique(np.asarray(free, dtype=np.int64))
    if not len(free) or not len(f):
        return v
    f = _faces(f)
    # the steps run compiled (fair_kernels.relax_steps): a patch's few hundred vertices cost
    # numpy call overhead, not arithmetic; L: the uniform Laplacian's CSR arrays
    relax_steps(v, f, free, *uniform_csr(f, len(v)), int(iterations), float(step))
    return v

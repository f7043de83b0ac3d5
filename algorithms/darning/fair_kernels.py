"""The fairing system of one hole patch, assembled compiled (numba): fair.py's small-system path.

For the free vertices f_i of a patch, fair.py solves (L^k_i)[f_i, free] x_free = -(L^k_i)[f_i, fixed]
x_fixed (frep.md §4 "Matching the curvature": U1, U2 or U3 = 0 with k_i = 1, 2 or 3, lower near
bare vertices). A hole's patch has tens to a few hundred free vertices; building L^k with sparse
matrix products, slicing its rows and columns and factorising it with SuperLU costs far more in
call overhead than in arithmetic. Here each row of L^k_i at a free vertex is built on its own as
a row vector times L, k_i - 1 times (a sparse vector: a work array and the list of its nonzeros),
and scattered into the dense (m, m) system matrix and the (m, 3) right-hand side; fair.py solves
it with dense LU. Same system as the sparse path, summed in another order (round-off only).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def ring_distance(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, bare: np.ndarray,
                  k: int) -> np.ndarray:
    """(n,) distance in rings from the ``bare`` vertices (boolean (n,)) over the edges of L (an
    entry L[a, b] or L[b, a] nonzero), capped at k; bare vertices themselves keep k (fair.py)."""
    n = indptr.shape[0] - 1
    dist = np.full(n, k, dtype=np.int64)
    seen = bare.copy()
    front = bare.copy()
    new = np.zeros(n, dtype=np.bool_)
    for j in range(1, k):  # sequential: ring after ring
        new[:] = False
        for a in range(n):
            for p in range(indptr[a], indptr[a + 1]):
                if data[p] == 0.0:
                    continue
                b = indices[p]
                if front[b]:
                    new[a] = True
                if front[a]:
                    new[b] = True
        for a in range(n):
            front[a] = new[a] and not seen[a]
            if front[a]:
                dist[a] = j
                seen[a] = True
    return dist


@numba.njit(cache=True)
def power_system(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, free: np.ndarray,
                 order: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(A, rhs): A[i, j] = (L^order[i])[free[i], free[j]], rhs[i] = -sum over fixed c of
    (L^order[i])[free[i], c] x[c] (x (n, 3) the current positions; fixed = not in ``free``)."""
    n = indptr.shape[0] - 1
    m = free.shape[0]
    where = np.full(n, -1, dtype=np.int64)
    for i in range(m):
        where[free[i]] = i
    A = np.zeros((m, m))
    rhs = np.zeros((m, 3))
    cur = np.zeros(n)
    nxt = np.zeros(n)
    in_cur = np.zeros(n, dtype=np.bool_)
    in_nxt = np.zeros(n, dtype=np.bool_)
    cur_list = np.empty(n, dtype=np.int64)
    nxt_list = np.empty(n, dtype=np.int64)
    for i in range(m):
        r = free[i]
        nc = 0
        for p in range(indptr[r], indptr[r + 1]):  # the row of L at free[i]
            c = indices[p]
            if not in_cur[c]:
                in_cur[c] = True
                cur_list[nc] = c
                nc += 1
            cur[c] += data[p]
        for _ in range(order[i] - 1):  # row vector times L
            nn = 0
            for q in range(nc):
                a = cur_list[q]
                w = cur[a]
                for p in range(indptr[a], indptr[a + 1]):
                    c = indices[p]
                    if not in_nxt[c]:
                        in_nxt[c] = True
                        nxt_list[nn] = c
                        nn += 1
                    nxt[c] += w * data[p]
                cur[a] = 0.0
                in_cur[a] = False
            for q in range(nn):
                c = nxt_list[q]
                cur_list[q] = c
                cur[c] = nxt[c]
                in_cur[c] = True
                nxt[c] = 0.0
                in_nxt[c] = False
            nc = nn
        for q in range(nc):
            c = cur_list[q]
            w = cur[c]
            j = where[c]
            if j >= 0:
                A[i, j] += w
            else:
                rhs[i, 0] -= w * x[c, 0]
                rhs[i, 1] -= w * x[c, 1]
                rhs[i, 2] -= w * x[c, 2]
            cur[c] = 0.0
            in_cur[c] = False
    return A, rhs


@numba.njit(cache=True)
def dense_solve(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, bool]:
    """x with A x = b (A (m, m), b (m, k)) by Gaussian elimination with partial pivoting, and
    whether A was regular (False: a pivot was exactly zero, x is then meaningless). Compiled
    rather than LAPACK: a patch's system (here) or a hole's RBF fit (implicit.py) has tens to
    hundreds of unknowns, where a threaded BLAS on a loaded machine spends milliseconds per call
    synchronising its threads (measured 90 ms per RBF fit against 4 ms)."""
    m = A.shape[0]
    nk = b.shape[1]
    a = A.copy()
    x = b.copy()
    for c in range(m):
        p = c
        best = abs(a[c, c])
        for r in range(c + 1, m):
            if abs(a[r, c]) > best:
                best = abs(a[r, c])
                p = r
        if best == 0.0:
            return x, False
        if p != c:
            for j in range(c, m):
                a[c, j], a[p, j] = a[p, j], a[c, j]
            for j in range(nk):
                x[c, j], x[p, j] = x[p, j], x[c, j]
        piv = a[c, c]
        for r in range(c + 1, m):
            f = a[r, c] / piv
            if f == 0.0:
                continue
            for j in range(c + 1, m):
                a[r, j] -= f * a[c, j]
            for j in range(nk):
                x[r, j] -= f * x[c, j]
    for c in range(m - 1, -1, -1):
        for j in range(nk):
            s = x[c, j]
            for q in range(c + 1, m):
                s -= a[c, q] * x[q, j]
            x[c, j] = s / a[c, c]
    return x, True


@numba.njit(cache=True)
def relax_steps(v: np.ndarray, f: np.ndarray, free: np.ndarray, indptr: np.ndarray, indices: np.ndarray,
                data: np.ndarray, iterations: int, step: float) -> None:
    """fair.tangential_relax's iterations on v (n, 3) in place: L (CSR, n x n) the uniform
    Laplacian; each free vertex moves ``step`` times its umbrella vector L v with the component
    along its vertex normal (the face normals summed, corner 0 of every face first, then 1, then 2)
    removed; all moves of an iteration from the same positions."""
    n = v.shape[0]
    m = free.shape[0]
    fn = np.empty((f.shape[0], 3))
    vn = np.empty((n, 3))
    d = np.empty((m, 3))
    for _ in range(iterations):  # sequential: each step starts from the previous positions
        for i in range(f.shape[0]):
            a, b, c = f[i, 0], f[i, 1], f[i, 2]
            u0, u1, u2 = v[b, 0] - v[a, 0], v[b, 1] - v[a, 1], v[b, 2] - v[a, 2]
            w0, w1, w2 = v[c, 0] - v[a, 0], v[c, 1] - v[a, 1], v[c, 2] - v[a, 2]
            fn[i, 0] = u1 * w2 - u2 * w1
            fn[i, 1] = u2 * w0 - u0 * w2
            fn[i, 2] = u0 * w1 - u1 * w0
        vn[:] = 0.0
        for k in range(3):
            for i in range(f.shape[0]):
                for j in range(3):
                    vn[f[i, k], j] += fn[i, j]
        for q in range(m):
            r = free[q]
            n0, n1, n2 = vn[r, 0], vn[r, 1], vn[r, 2]
            ln = max(np.sqrt(n0 * n0 + n1 * n1 + n2 * n2), 1e-300)
            n0, n1, n2 = n0 / ln, n1 / ln, n2 / ln
            s0 = s1 = s2 = 0.0
            for p in range(indptr[r], indptr[r + 1]):
                c = indices[p]
                s0 += data[p] * v[c, 0]
                s1 += data[p] * v[c, 1]
                s2 += data[p] * v[c, 2]
            t = s0 * n0 + s1 * n1 + s2 * n2
            d[q, 0], d[q, 1], d[q, 2] = s0 - t * n0, s1 - t * n1, s2 - t * n2
        for q in range(m):
            for j in range(3):
                v[free[q], j] += step * d[q, j]


@numba.njit(cache=True)
def _csr_with_diagonal(rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, dvals: np.ndarray,
                       n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR arrays of the entries (rows, cols, vals) (sorted by row then column) plus one diagonal
    entry dvals[r] per row, placed after the row's entries at columns <= r; exact zeros dropped."""
    cnt = np.zeros(n + 1, dtype=np.int64)
    m = rows.shape[0]
    indices = np.empty(m + n, dtype=np.int64)
    data = np.empty(m + n)
    q = 0
    p = 0
    for r in range(n):
        cnt[r] = q
        while p < m and rows[p] == r and cols[p] <= r:
            if vals[p] != 0.0:
                indices[q] = cols[p]
                data[q] = vals[p]
                q += 1
            p += 1
        if dvals[r] != 0.0:
            indices[q] = r
            data[q] = dvals[r]
            q += 1
        while p < m and rows[p] == r:
            if vals[p] != 0.0:
                indices[q] = cols[p]
                data[q] = vals[p]
                q += 1
            p += 1
    cnt[n] = q
    return cnt, indices[:q], data[:q]


@numba.njit(cache=True)
def uniform_csr(faces: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """fair.uniform_laplacian's CSR arrays (indptr, indices, data): L = D^-1 A - I, columns sorted,
    rows of vertices without edges empty."""
    nf = faces.shape[0]
    und = np.empty(3 * nf, dtype=np.int64)
    for i in range(nf):
        for k in range(3):
            a, b = faces[i, k], faces[i, (k + 1) % 3]
            und[3 * i + k] = min(a, b) * n + max(a, b)
    und = np.unique(und)
    both = np.empty(2 * und.shape[0], dtype=np.int64)
    for i in range(und.shape[0]):
        a, b = und[i] // n, und[i] % n
        both[2 * i] = a * n + b
        both[2 * i + 1] = b * n + a
    both = np.sort(both)
    rows = both // n
    cols = both % n
    deg = np.zeros(n, dtype=np.int64)
    for r in rows:
        deg[r] += 1
    vals = np.empty(rows.shape[0])
    for i in range(rows.shape[0]):
        vals[i] = 1.0 / deg[rows[i]]
    dvals = np.zeros(n)
    for r in range(n):
        if deg[r] > 0:
            dvals[r] = -1.0
    return _csr_with_diagonal(rows, cols, vals, dvals, n)


@numba.njit(cache=True)
def cotan_csr(v: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """fair.cotan_laplacian's CSR arrays: L = M^-1 (C - diag(C 1)), the same sums in the same order
    (C_ab over the faces in corner-major order, the row sums of C over sorted columns, M a third of
    the incident faces' areas), exact zeros dropped."""
    n = v.shape[0]
    nf = faces.shape[0]
    dbl = np.empty(nf)
    for i in range(nf):
        a, b, c = faces[i, 0], faces[i, 1], faces[i, 2]
        u0, u1, u2 = v[b, 0] - v[a, 0], v[b, 1] - v[a, 1], v[b, 2] - v[a, 2]
        w0, w1, w2 = v[c, 0] - v[a, 0], v[c, 1] - v[a, 1], v[c, 2] - v[a, 2]
        x0, x1, x2 = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0
        dbl[i] = np.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    floor = max(dbl.max() * 1e-12, 1e-300) if nf else 1.0
    keys = np.empty(6 * nf, dtype=np.int64)
    vals = np.empty(6 * nf)
    for k in range(3):  # the corner k is opposite the edge (k+1, k+2)
        for i in range(nf):
            o, a, b = faces[i, k], faces[i, (k + 1) % 3], faces[i, (k + 2) % 3]
            u0, u1, u2 = v[a, 0] - v[o, 0], v[a, 1] - v[o, 1], v[a, 2] - v[o, 2]
            w0, w1, w2 = v[b, 0] - v[o, 0], v[b, 1] - v[o, 1], v[b, 2] - v[o, 2]
            cot = (u0 * w0 + u1 * w1 + u2 * w2) / max(dbl[i], floor)
            cot = min(max(cot, -1e3), 1e3) / 2
            keys[2 * k * nf + i] = a * n + b
            keys[(2 * k + 1) * nf + i] = b * n + a
            vals[2 * k * nf + i] = cot
            vals[(2 * k + 1) * nf + i] = cot
    order = np.argsort(keys, kind="mergesort")
    uk = np.empty(6 * nf, dtype=np.int64)
    cv = np.zeros(6 * nf)
    m = -1
    last = -1
    for j in range(6 * nf):
        key = keys[order[j]]
        if key != last:
            m += 1
            uk[m] = key
            last = key
        cv[m] += vals[order[j]]
    m += 1
    rows = uk[:m] // n
    cols = uk[:m] % n
    dsum = np.zeros(n)
    for j in range(m):
        dsum[rows[j]] += cv[j]
    area = np.zeros(n)
    for i in range(nf):
        for k in range(3):
            area[faces[i, k]] += dbl[i] / 6
    inv = np.zeros(n)
    for r in range(n):
        if area[r] > 0:
            inv[r] = 1.0 / area[r]
    off = np.empty(m)
    for j in range(m):
        off[j] = inv[rows[j]] * cv[j]
    dvals = np.empty(n)
    for r in range(n):
        dvals[r] = inv[r] * -dsum[r]
    return _csr_with_diagonal(rows, cols, off, dvals, n)

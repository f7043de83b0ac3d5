"""Quality of a straight bridge and the factors of the basic task (spec/repair.md §3, eqs. 1-10).

Everything here is the plain, readable reference: one function per factor, vectorised over the
leading axes of its arguments. The field kernels (indicator.py) fuse the same formulas for speed
and are tested against these.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..params import FieldParams
from ..records import BridgeFactors

Arr = NDArray[np.float64]


def _unit(a: Arr) -> Arr:
    n = np.linalg.norm(a, axis=-1, keepdims=True)
    return np.divide(a, n, out=np.zeros_like(a, dtype=np.float64), where=n > 0)


def q1(length: Arr | float, lc: float, kernel: str = "gauss") -> Arr:
    """(3) shortness: q1 >= 0, decreasing, q1(0) = 1, q1(inf) = 0.

    "gauss": exp(-(L/Lc)^2) (default, decays fast: see spec §5 on equilibria);
    "cauchy": the heavy-tailed 1 / (1 + (L/Lc)^2).
    """
    x2 = (np.asarray(length, dtype=np.float64) / lc) ** 2
    if kernel == "gauss":
        return np.exp(-x2)
    if kernel == "cauchy":
        return 1.0 / (1.0 + x2)
    raise ValueError(f"unknown q1 kernel {kernel!r}")


def log_q1(length: Arr | float, lc: float, kernel: str = "gauss") -> Arr:
    """log of (3), without the underflow of :func:`q1`: a ranking by q1 of lengths many L_c long
    (exp(-(L/Lc)^2) is 0.0 from L = 27 Lc on) still orders them, shortest first."""
    x2 = (np.asarray(length, dtype=np.float64) / lc) ** 2
    if kernel == "gauss":
        return -x2
    if kernel == "cauchy":
        return -np.log1p(x2)
    raise ValueError(f"unknown q1 kernel {kernel!r}")


def g0(kt: float) -> float:
    """G(0) = k_t / (1 - k_t), the weight of a free point at distance 0 (eq. 4)."""
    return kt / (1.0 - kt)


def free_point_g(r: Arr | float, kt: float, rc: float, kernel: str = "gauss") -> Arr:
    """(4) scalar field of one free point: G >= 0, decreasing, G(0) = k_t/(1-k_t), G(inf) = 0."""
    x2 = (np.asarray(r, dtype=np.float64) / rc) ** 2
    if kernel == "gauss":
        return g0(kt) * np.exp(-x2)
    if kernel == "cauchy":
        return g0(kt) / (1.0 + x2)
    raise ValueError(f"unknown G kernel {kernel!r}")


def g_cutoff(rc: float, kernel: str = "gauss") -> float:
    """Distance beyond which G < 1e-4 G(0): free points farther than this are ignored."""
    return rc * (3.035 if kernel == "gauss" else 100.0)


def q2_segment(a: Arr, b: Arr, free_points: Arr, *, kt: float, rc: float, kernel: str = "gauss",
               samples: int = 16, tree=None) -> float:
    """(4) effective length of the segment a->b through free points:
    q2 = integral over the segment of dl / (1 + sum_i G(|P_i - Y(l)|)).

    Midpoint rule with ``samples`` points; the free points near each sample come from a
    scipy cKDTree (built here unless ``tree`` is given). Without free points q2 = |b - a|.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    length = float(np.linalg.norm(b - a))
    fp = np.asarray(free_points, dtype=np.float64).reshape(-1, 3)
    if len(fp) == 0 or length == 0:
        return length
    if tree is None:
        from scipy.spatial import cKDTree

        tree = cKDTree(fp)
    t = (np.arange(samples) + 0.5) / samples
    y = a + t[:, None] * (b - a)
    near = tree.query_ball_point(y, g_cutoff(rc, kernel))
    gs = np.array([free_point_g(np.linalg.norm(fp[idx] - yk, axis=1), kt, rc, kernel).sum() if idx else 0.0
                   for yk, idx in zip(y, near)])
    return float(length * np.mean(1.0 / (1.0 + gs)))


def s_vectors(a: Arr, tau_a: Arr, b: Arr, tau_b: Arr) -> tuple[Arr, Arr]:
    """(1a) s_A = u_AB x tau_A, (1b) s_B = u_BA x tau_B (not normalised: |s| = |sin(u, tau)|)."""
    u = _unit(np.asarray(b, dtype=np.float64) - np.asarray(a, dtype=np.float64))
    return np.cross(u, tau_a), np.cross(-u, tau_b)


def q_topological(a: Arr, tau_a: Arr, b: Arr, tau_b: Arr) -> Arr:
    """(2) q_T = s_A . s_B; the connection is topologically possible only if q_T > 0."""
    sa, sb = s_vectors(a, tau_a, b, tau_b)
    return np.einsum("...k,...k->...", sa, sb)


def q3(n_x: Arr, d: Arr) -> Arr:
    """(5) q3 = |sin(n_X, d)| = |n_X x d| (unit vectors)."""
    return np.linalg.norm(np.cross(n_x, d), axis=-1)


def q4(s_o: Arr, n_o: Arr) -> Arr:
    """(7) q4 = (1 + s_O . n_O) / 2: the bridge continues the island's surface at O."""
    return 0.5 * (1.0 + np.einsum("...k,...k->...", s_o, n_o))


def basic_task(x: Arr, n_x: Arr, o: Arr, tau_o: Arr, n_o: Arr, params: FieldParams, lc: float, *,
               q2: Arr | float | None = None) -> dict[str, Arr]:
    """Factors of the basic task (§3): a point X with a trial unit normal n_X, a source O.

    Returns a dict with d (6), L, s_O, s_X, qT, q1, q2, q12 (8), q3 (5), q4 (7), Q (9) and
    Q10 = (n_X . s_O) q12 (1 + k_i q4) (10), which equals Q. ``q2`` is the effective length
    (defaults to L, light mode).
    """
    r = np.asarray(o, dtype=np.float64) - np.asarray(x, dtype=np.float64)
    L = np.linalg.norm(r, axis=-1)
    d = _unit(r)  # (6)
    s_o = np.cross(tau_o, d)  # s_O = u_OX x tau_O = tau_O x d
    nd = np.einsum("...k,...k->...", n_x, d)
    s_x = _unit(n_x - nd[..., None] * d)
    qt = np.einsum("...k,...k->...", s_x, s_o)  # (2)
    q2v = L if q2 is None else np.asarray(q2, dtype=np.float64)
    q12 = q1(q2v, lc, params.q1_kernel)  # (8)
    q3v = q3(n_x, d)  # (5)
    q4v = q4(s_o, n_o)  # (7)
    Q = qt * q12 * q3v * (1.0 + params.ki * q4v)  # (9)
    Q10 = np.einsum("...k,...k->...", n_x, s_o) * q12 * (1.0 + params.ki * q4v)  # (10)
    return {"d": d, "L": L, "s_O": s_o, "s_X": s_x, "qT": qt, "q1": q1(L, lc, params.q1_kernel), "q2": q2v,
            "q12": q12, "q3": q3v, "q4": q4v, "Q": Q, "Q10": Q10}


def bridge_factors(a: Arr, tau_a: Arr, n_a: Arr, b: Arr, tau_b: Arr, n_b: Arr, params: FieldParams,
                   free_points: Arr | None = None, *, lc: float | None = None) -> BridgeFactors:
    """Quality of the straight bridge A -> B (eqs. 1-10), every factor separately.

    The bridge is the basic task with X = A, n_X = s_A/|s_A| (1a: the normal the bridge must have
    at A to join A's island smoothly) and O = B: q_T = s_A . s_B (2); q3 = |n_X x d| (5) = 1 since
    s_A is perpendicular to d; q4 = (1 + s_B . n_B)/2 (7) judges the continuation at B; n_a is
    accepted for symmetry (q4 at A would use it) but (9) uses q4 at the source O = B only.
    q2 (4) uses the free points in full mode (cKDTree), q12 = q1(q2) (8); in light mode q12 = q1(L).
    ``lc`` defaults to params.lc, else to the bridge length (q1 = exp(-1)).
    """
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    tau_a, tau_b = np.asarray(tau_a, dtype=np.float64), np.asarray(tau_b, dtype=np.float64)
    L = float(np.linalg.norm(b - a))
    lc_ = lc if lc is not None else (params.lc if params.lc is not None else max(L, 1e-12))
    sa, sb = s_vectors(a, tau_a, b, tau_b)
    qt = float(sa @ sb)  # (2)
    if params.use_free_points and free_points is not None and len(free_points):
        q2v = q2_segment(a, b, free_points, kt=params.kt, rc=params.rc_factor * lc_, kernel=params.g_kernel)
    else:
        q2v = L
    q1v = float(q1(L, lc_, params.q1_kernel))
    q12 = float(q1(q2v, lc_, params.q1_kernel))  # (8)
    d = (b - a) / L if L > 0 else np.zeros(3)
    nsa = float(np.linalg.norm(sa))
    n_x = sa / nsa if nsa > 0 else np.zeros(3)
    q3v = float(np.linalg.norm(np.cross(n_x, d)))  # (5)
    q4v = float(0.5 * (1.0 + sb @ np.asarray(n_b, dtype=np.float64)))  # (7), s_O = s_B at O = B
    Q = qt * q12 * q3v * (1.0 + params.ki * q4v)  # (9)
    return BridgeFactors(qt, q1v, float(q2v), q12, q3v, q4v, float(Q))

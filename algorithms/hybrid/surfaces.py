"""Parametric surfaces R(u, v) on a parameter rectangle (spec/hybrid.md §1 (1), §5 (8), (9)).

A :class:`Surface` evaluates on numpy arrays of u and v (any equal shapes) and returns points of
shape (..., 3). Periodic directions are declared (``periodic_u`` / ``periodic_v``): the sides
u = a and u = b (or v = c and v = d) are the same curve in space and the mesher welds them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

Eval = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


@dataclass(frozen=True, eq=False)
class Surface:
    """R(u, v) on [a, b] × [c, d]."""

    name: str
    evaluate: Eval = field(repr=False)
    domain: tuple[float, float, float, float]
    periodic_u: bool = False
    periodic_v: bool = False

    def __post_init__(self) -> None:
        a, b, c, d = (float(x) for x in self.domain)
        if not (np.isfinite([a, b, c, d]).all() and b > a and d > c):
            raise ValueError(f"domain: need a < b and c < d, got {self.domain}")
        object.__setattr__(self, "domain", (a, b, c, d))

    def __call__(self, u: ArrayLike, v: ArrayLike) -> NDArray[np.float64]:
        u, v = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
        out = np.asarray(self.evaluate(u, v), dtype=np.float64)
        if out.shape != u.shape + (3,):
            raise ValueError(f"surface {self.name!r} returned shape {out.shape}, expected {u.shape + (3,)}")
        return out

    @property
    def size(self) -> float:
        """The model size: the bounding-box diagonal of a 33 × 33 sample."""
        a, b, c, d = self.domain
        uu, vv = np.meshgrid(np.linspace(a, b, 33), np.linspace(c, d, 33), indexing="ij")
        p = self(uu, vv).reshape(-1, 3)
        return float(np.linalg.norm(p.max(0) - p.min(0)))

    def derivatives(self, u: ArrayLike, v: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(R_u, R_v) by central differences (one-sided at the rectangle sides)."""
        a, b, c, d = self.domain
        u = np.asarray(u, dtype=np.float64)
        v = np.asarray(v, dtype=np.float64)
        hu, hv = 1e-6 * (b - a), 1e-6 * (d - c)
        u0, u1 = np.maximum(u - hu, a), np.minimum(u + hu, b)
        v0, v1 = np.maximum(v - hv, c), np.minimum(v + hv, d)
        ru = (self(u1, v) - self(u0, v)) / (u1 - u0)[..., None]
        rv = (self(u, v1) - self(u, v0)) / (v1 - v0)[..., None]
        return ru, rv


def bernstein(n: int, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """(..., n+1) Bernstein polynomials B_i^n(t) = C(n, i) t^i (1 − t)^(n − i)."""
    t = np.asarray(t, dtype=np.float64)[..., None]
    i = np.arange(n + 1)
    binom = np.array([math.comb(n, k) for k in range(n + 1)], dtype=np.float64)
    return binom * t**i * (1.0 - t) ** (n - i)


def _bernstein_rows(n: int, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N, n+1) Bernstein polynomials of degree n at t (N,), by the recurrence
    B_i^k = (1 − t) B_i^(k−1) + t B_(i−1)^(k−1) (no powers: fast and stable)."""
    s = 1.0 - t
    cols = [np.ones_like(t)]
    for _k in range(n):  # contiguous 1D columns: a few microseconds per operation for small N
        cols = [s * cols[0]] + [s * cols[i] + t * cols[i - 1] for i in range(1, len(cols))] + [t * cols[-1]]
    return np.stack(cols, axis=1)


def bezier(control: ArrayLike, *, name: str = "bezier") -> Surface:
    """A tensor-product Bezier patch of any degree (8): p(u,v) = Σ_i Σ_j B_i^n(u) B_j^m(v) P_ij.

    control: (n+1, m+1, 3) control points, i-major; (u, v) ∈ [0, 1]².
    """
    P = np.array(control, dtype=np.float64)
    if P.ndim != 3 or P.shape[2] != 3 or P.shape[0] < 2 or P.shape[1] < 2:
        raise ValueError(f"control: need an (n+1, m+1, 3) array with n, m >= 1, got shape {P.shape}")
    n, m = P.shape[0] - 1, P.shape[1] - 1
    P.setflags(write=False)
    Pf = P.reshape(n + 1, (m + 1) * 3)

    def ev(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
        shape = u.shape
        Bu = _bernstein_rows(n, u.reshape(-1))  # B_i^n(u)
        Bv = _bernstein_rows(m, v.reshape(-1))  # B_j^m(v)
        Q = (Bu @ Pf).reshape(-1, m + 1, 3)
        out = np.matmul(Bv[:, None, :], Q)[:, 0, :]  # Σ_i Σ_j B_i^n(u) B_j^m(v) P_ij  (8)
        return out.reshape(shape + (3,))

    return Surface(name, ev, (0.0, 1.0, 0.0, 1.0))


def de_casteljau(control: ArrayLike, u: float, v: float) -> NDArray[np.float64]:
    """Reference evaluation of a Bezier patch by repeated linear interpolation (for tests)."""
    P = np.array(control, dtype=np.float64)
    while P.shape[0] > 1:
        P = (1 - u) * P[:-1] + u * P[1:]
    Q = P[0]
    while Q.shape[0] > 1:
        Q = (1 - v) * Q[:-1] + v * Q[1:]
    return Q[0]


def cone(r1: float, r2: float, length: float, *, v0: float = 0.0, name: str = "cone") -> Surface:
    """The conical shell (9): x = r(u) cos v, y = u, z = r(u) sin v, r(u) = r1 + (r2 − r1) u / l.

    u ∈ [0, l], v ∈ [v0, v0 + 2π] (periodic in v; v0 places the seam).
    """
    if r1 <= 0 or r2 <= 0 or length <= 0:
        raise ValueError("cone: r1, r2 and length must be positive")

    def ev(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
        r = r1 + (r2 - r1) * u / length
        return np.stack([r * np.cos(v), u, r * np.sin(v)], axis=-1)

    return Surface(name, ev, (0.0, float(length), v0, v0 + 2 * math.pi), periodic_v=True)


def cylinder(radius: float, z0: float, z1: float, *, v0: float = 0.0, name: str = "cylinder") -> Surface:
    """x = R cos v, y = R sin v, z = u; u ∈ [z0, z1], v ∈ [v0, v0 + 2π] (periodic in v)."""
    if radius <= 0:
        raise ValueError("cylinder: radius must be positive")

    def ev(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([radius * np.cos(v), radius * np.sin(v), u], axis=-1)

    return Surface(name, ev, (z0, z1, v0, v0 + 2 * math.pi), periodic_v=True)


def sphere(radius: float, lat0: float, lat1: float, *, lon0: float = 0.0, lon1: float = 2 * math.pi,
           name: str = "sphere") -> Surface:
    """x = R cos u cos v, y = R cos u sin v, z = R sin u; u latitude in [lat0, lat1] (inside
    (−π/2, π/2): no degenerate poles), v longitude in [lon0, lon1] (periodic when it spans 2π)."""
    if radius <= 0 or not (-math.pi / 2 < lat0 < lat1 < math.pi / 2):
        raise ValueError("sphere: radius > 0 and −π/2 < lat0 < lat1 < π/2 required")

    def ev(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
        return radius * np.stack([np.cos(u) * np.cos(v), np.cos(u) * np.sin(v), np.sin(u)], axis=-1)

    periodic = abs((lon1 - lon0) - 2 * math.pi) < 1e-12
    return Surface(name, ev, (lat0, lat1, lon0, lon1), periodic_v=periodic)


def torus(major: float, minor: float, *, u0: float = 0.0, v0: float = 0.0, name: str = "torus") -> Surface:
    """((R + r cos u) cos v, (R + r cos u) sin v, r sin u), periodic in u and v."""
    if not 0 < minor < major:
        raise ValueError("torus: need 0 < minor < major")

    def ev(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
        w = major + minor * np.cos(u)
        return np.stack([w * np.cos(v), w * np.sin(v), minor * np.sin(u)], axis=-1)

    return Surface(name, ev, (u0, u0 + 2 * math.pi, v0, v0 + 2 * math.pi), periodic_u=True, periodic_v=True)


def from_functions(x: Callable, y: Callable, z: Callable, domain: tuple[float, float, float, float], *,
                   periodic_u: bool = False, periodic_v: bool = False, name: str = "expression") -> Surface:
    """A surface from three callables of (u, v) (e.g. compiled expressions of algorithms.expr)."""

    def ev(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([np.broadcast_to(np.asarray(f(u, v), dtype=np.float64), u.shape) for f in (x, y, z)],
                        axis=-1)

    return Surface(name, ev, domain, periodic_u=periodic_u, periodic_v=periodic_v)


# The paper's Bezier patch (Fig. 4), i-major control points.
PAPER_BEZIER = np.array([
    [(0, -1, -1), (0, -1, -0.5), (0, -1, 0.5), (0, -1, 1)],
    [(4, -1, -1), (4, -1, -0.5), (4, -1, 0.5), (4, -1, 1)],
    [(4, 1, -1), (4, 1, -0.5), (4, 1, 0.5), (4, 1, 1)],
    [(0, 1, -1), (0, 1, -0.5), (0, 1, 0.5), (0, 1, 1)],
], dtype=np.float64)

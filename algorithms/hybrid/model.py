"""A hybrid model: a parametric surface R(u, v) trimmed by an implicit F(x, y, z) (spec §1)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .surfaces import Surface

Implicit = Callable[[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


@dataclass(frozen=True, eq=False)
class HybridModel:
    """surface: R(u, v). trim: F(x, y, z) > 0 on the kept part (None keeps the whole rectangle)."""

    name: str
    surface: Surface
    trim: Implicit | None = field(default=None, repr=False)
    description: str = ""

    def F(self, points: ArrayLike) -> NDArray[np.float64]:
        p = np.asarray(points, dtype=np.float64)
        if self.trim is None:
            return np.ones(p.shape[:-1])
        out = self.trim(p[..., 0], p[..., 1], p[..., 2])
        return np.broadcast_to(np.asarray(out, dtype=np.float64), p.shape[:-1]).copy()

    def W(self, u: ArrayLike, v: ArrayLike) -> NDArray[np.float64]:
        """W(u, v) = F(R(u, v)) ∧ [the parameter rectangle]  (5).

        The rectangle factors vanish exactly on the sides of P, which are lines of the background
        grid, so the mesher uses them as border segments directly and W here is F(R(u, v)) on P.
        """
        return self.F(self.surface(u, v))

    def bisect(self, p: ArrayLike, q: ArrayLike, *, iterations: int = 60) -> NDArray[np.float64]:
        """Zero crossings of W on the parameter segments p→q (arrays (K, 2)), where W changes sign.

        Root finding in the segment parameter t, vectorised over K: the Illinois variant of regula
        falsi (superlinear), keeping the sign-change bracket, until the bracket is below 1e-15 or
        W is exactly zero. Deterministic: the same segment always gives the same point.
        """
        p = np.asarray(p, dtype=np.float64).reshape(-1, 2)
        q = np.asarray(q, dtype=np.float64).reshape(-1, 2)
        n = len(p)
        lo, hi = np.zeros(n), np.ones(n)
        flo = self.W(p[:, 0], p[:, 1])
        fhi = self.W(q[:, 0], q[:, 1])
        t = np.full(n, 0.5)
        side = np.zeros(n, dtype=np.int8)  # the end kept last time (Illinois halving)
        active = np.ones(n, dtype=bool)
        for _ in range(iterations):
            if not active.any():
                break
            i = np.flatnonzero(active)
            den = fhi[i] - flo[i]
            tt = np.where(den != 0, lo[i] - flo[i] * (hi[i] - lo[i]) / np.where(den != 0, den, 1.0),
                          0.5 * (lo[i] + hi[i]))
            bad = ~((tt > lo[i]) & (tt < hi[i]))
            tt[bad] = 0.5 * (lo[i] + hi[i])[bad]
            x = p[i] + tt[:, None] * (q[i] - p[i])
            f = self.W(x[:, 0], x[:, 1])
            t[i] = tt
            same_lo = (f >= 0) == (flo[i] >= 0)
            # move the end on the side of f; halve the other end's value if it was kept twice
            j = i[same_lo]
            lo[j], flo[j] = tt[same_lo], f[same_lo]
            keep_hi = side[j] == 1
            fhi[j[keep_hi]] *= 0.5
            side[j] = 1
            k = i[~same_lo]
            hi[k], fhi[k] = tt[~same_lo], f[~same_lo]
            keep_lo = side[k] == -1
            flo[k[keep_lo]] *= 0.5
            side[k] = -1
            active[i] = ~((f == 0) | (hi[i] - lo[i] < 1e-15))
        return p + t[:, None] * (q - p)

    def project(self, uv: ArrayLike, direction: ArrayLike, reach: ArrayLike) -> tuple[NDArray, NDArray]:
        """Move points onto W = 0 along ±direction (root finding in the bracket uv ± reach·direction).

        Returns (points (K, 2), ok (K,)): ok is False where no sign change was found in the bracket
        (grown up to 4 × reach); those points are returned unchanged.
        """
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        d = np.asarray(direction, dtype=np.float64).reshape(-1, 2)
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        reach = np.broadcast_to(np.asarray(reach, dtype=np.float64), (len(uv),))
        out = uv.copy()
        ok = np.zeros(len(uv), dtype=bool)
        a, b, c, dd = self.surface.domain
        lo_b, hi_b = np.array([a, c]), np.array([b, dd])
        for grow in (1.0, 2.0, 4.0):
            todo = ~ok
            if not todo.any():
                break
            # try the half-brackets towards both sides, nearest root first
            for sgn in (1.0, -1.0):
                todo = ~ok
                if not todo.any():
                    break
                p = uv[todo]
                q = np.clip(p + sgn * grow * reach[todo, None] * d[todo], lo_b, hi_b)
                wp = self.W(p[:, 0], p[:, 1])
                wq = self.W(q[:, 0], q[:, 1])
                change = (wp >= 0) != (wq >= 0)
                if change.any():
                    idx = np.flatnonzero(todo)[change]
                    out[idx] = self.bisect(p[change], q[change])
                    ok[idx] = True
        return out, ok

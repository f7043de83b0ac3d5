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

    def bisect(self, p: ArrayLike, q: ArrayLike, *, samples: int | None = None, rounds: int | None = None,
               wp: ArrayLike | None = None, wq: ArrayLike | None = None) -> NDArray[np.float64]:
        """Zero crossings of W on the parameter segments p→q (arrays (K, 2)), where W changes sign.

        Root finding in the segment parameter t, vectorised over K and over the samples: each round
        evaluates W at `samples` - 1 interior points of every bracket (one surface and one F call for
        all of them: for a few segments the cost of a call barely depends on its length) and keeps the
        first sub-interval with a sign change. samples defaults to 128 for a few segments, fewer for
        many (about 2048 points a call: then the cost is in the points, not in the calls), and rounds
        to what brings the bracket below 1e-6 of the segment (128⁻³ ≈ 5e-7); then Illinois regula falsi
        inside it shrinks the bracket below 1e-14 (the border accuracy of §2, checked in the mesher's
        report). wp, wq: W at p and q if the caller has them. Deterministic.
        """
        p = np.asarray(p, dtype=np.float64).reshape(-1, 2)
        q = np.asarray(q, dtype=np.float64).reshape(-1, 2)
        n = len(p)
        if n == 0:
            return p.copy()
        d = q - p
        lo, hi = np.zeros(n), np.ones(n)
        flo = self.W(p[:, 0], p[:, 1]) if wp is None else np.asarray(wp, dtype=np.float64).copy()
        fhi = self.W(q[:, 0], q[:, 1]) if wq is None else np.asarray(wq, dtype=np.float64).copy()
        if samples is None:
            samples = int(np.clip(2048 // n, 8, 128))
        if rounds is None:
            rounds = int(np.ceil(6.0 / np.log10(samples)))
        s = np.linspace(0.0, 1.0, samples + 1)[1:-1]  # interior fractions of the bracket
        for _ in range(rounds):
            t = lo[:, None] + (hi - lo)[:, None] * s[None, :]  # (K, S-1)
            x = p[:, None, :] + t[..., None] * d[:, None, :]
            f = self.W(x[..., 0], x[..., 1])
            tt = np.concatenate([lo[:, None], t, hi[:, None]], axis=1)
            ff = np.concatenate([flo[:, None], f, fhi[:, None]], axis=1)
            sg = ff >= 0
            change = sg[:, 1:] != sg[:, :-1]
            has = change.any(axis=1)
            j = np.where(has, change.argmax(axis=1), 0)
            rows = np.arange(n)
            lo = np.where(has, tt[rows, j], lo)
            hi = np.where(has, tt[rows, j + 1], hi)
            flo = np.where(has, ff[rows, j], flo)
            fhi = np.where(has, ff[rows, j + 1], fhi)
        # then the Illinois variant of regula falsi inside the last bracket, until it is below 1e-14 of the
        # segment (superlinear: two or three calls where W is smooth; it also converges at kinks of W)
        side = np.zeros(n, dtype=np.int8)
        active = (flo != 0) & (fhi != 0)
        for _ in range(40):
            i = np.flatnonzero(active)
            if not len(i):
                break
            den = fhi[i] - flo[i]
            tt = lo[i] - flo[i] * (hi[i] - lo[i]) / np.where(den != 0, den, 1.0)
            bad = (den == 0) | ~((tt > lo[i]) & (tt < hi[i]))
            tt[bad] = 0.5 * (lo[i] + hi[i])[bad]
            x = p[i] + tt[:, None] * d[i]
            f = self.W(x[:, 0], x[:, 1])
            same = (f >= 0) == (flo[i] >= 0)
            j = i[same]
            lo[j], flo[j] = tt[same], f[same]
            fhi[j[side[j] == 1]] *= 0.5
            side[j] = 1
            k = i[~same]
            hi[k], fhi[k] = tt[~same], f[~same]
            flo[k[side[k] == -1]] *= 0.5
            side[k] = -1
            active[i] = (f != 0) & (hi[i] - lo[i] > 1e-14)
        t = np.where(np.abs(flo) <= np.abs(fhi), lo, hi)
        return p + t[:, None] * d

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
            todo = np.flatnonzero(~ok)
            if not len(todo):
                break
            # both half-brackets in one call; the one along +direction first
            p = uv[todo]
            step = grow * reach[todo, None] * d[todo]
            q1, q2 = np.clip(p + step, lo_b, hi_b), np.clip(p - step, lo_b, hi_b)
            m = len(p)
            w = self.W(np.r_[p[:, 0], q1[:, 0], q2[:, 0]], np.r_[p[:, 1], q1[:, 1], q2[:, 1]])
            wp, w1, w2 = w[:m], w[m:2 * m], w[2 * m:]
            c1 = (wp >= 0) != (w1 >= 0)
            c2 = ~c1 & ((wp >= 0) != (w2 >= 0))
            ch = c1 | c2
            if ch.any():
                q = np.where(c1[:, None], q1, q2)[ch]
                wq = np.where(c1, w1, w2)[ch]
                out[todo[ch]] = self.bisect(p[ch], q, wp=wp[ch], wq=wq)
                ok[todo[ch]] = True
        return out, ok

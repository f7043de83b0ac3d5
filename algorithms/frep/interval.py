"""Interval arithmetic on numpy arrays (spec/frep.md §2: "surely outside" by interval extension).

An :class:`Interval` holds element-wise lower and upper bounds ``lo <= hi`` (arrays of one shape
or scalars). Every operation returns an interval that encloses all values of the operation over
its operands' intervals, so an interval extension built from these operations can prove a box
outside the object (upper bound < 0) and never drops a box that holds surface. Rounding is
widened outward by a few ulps so that the enclosure also survives floating point.

The operators and the method names (``sqrt``, ``exp``, ``minimum`` ...) are those that
:mod:`algorithms.expr` calls in interval mode.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

_INF = np.inf


def _down(a: Any) -> Any:
    return np.nextafter(np.nextafter(a, -_INF), -_INF)


def _up(a: Any) -> Any:
    return np.nextafter(np.nextafter(a, _INF), _INF)


class Interval:
    """Element-wise closed intervals [lo, hi]."""

    __slots__ = ("lo", "hi")
    __array_ufunc__ = None  # numpy scalars/arrays on the left defer to our reflected operators

    def __init__(self, lo: ArrayLike, hi: ArrayLike | None = None) -> None:
        lo_a = np.asarray(lo, dtype=np.float64)
        hi_a = lo_a if hi is None else np.asarray(hi, dtype=np.float64)
        self.lo, self.hi = np.broadcast_arrays(lo_a, hi_a)

    # -- helpers -----------------------------------------------------------------------------
    @staticmethod
    def of(x: Any) -> Interval:
        return x if isinstance(x, Interval) else Interval(x, x)

    def __repr__(self) -> str:
        return f"Interval({self.lo!r}, {self.hi!r})"

    @property
    def mid(self) -> np.ndarray:
        return 0.5 * (self.lo + self.hi)

    @property
    def width(self) -> np.ndarray:
        return self.hi - self.lo

    def contains(self, x: ArrayLike) -> np.ndarray:
        x = np.asarray(x)
        return (self.lo <= x) & (x <= self.hi)

    def __getitem__(self, idx: Any) -> Interval:
        return Interval(self.lo[idx], self.hi[idx])

    # -- arithmetic ----------------------------------------------------------------------------
    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __pos__(self) -> Interval:
        return self

    def __add__(self, other: Any) -> Interval:
        o = Interval.of(other)
        return Interval(_down(self.lo + o.lo), _up(self.hi + o.hi))

    __radd__ = __add__

    def __sub__(self, other: Any) -> Interval:
        o = Interval.of(other)
        return Interval(_down(self.lo - o.hi), _up(self.hi - o.lo))

    def __rsub__(self, other: Any) -> Interval:
        return Interval.of(other) - self

    def __mul__(self, other: Any) -> Interval:
        o = Interval.of(other)
        with np.errstate(invalid="ignore"):
            p = np.stack(np.broadcast_arrays(self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi))
        p = np.where(np.isnan(p), 0.0, p)  # 0 * inf: the product of the bounds is 0
        return Interval(_down(p.min(axis=0)), _up(p.max(axis=0)))

    __rmul__ = __mul__

    def reciprocal(self) -> Interval:
        zero_in = (self.lo <= 0) & (self.hi >= 0)
        with np.errstate(divide="ignore"):
            lo = np.where(zero_in, -_INF, _down(1.0 / self.hi))
            hi = np.where(zero_in, _INF, _up(1.0 / self.lo))
        return Interval(lo, hi)

    def __truediv__(self, other: Any) -> Interval:
        return self * Interval.of(other).reciprocal()

    def __rtruediv__(self, other: Any) -> Interval:
        return Interval.of(other) * self.reciprocal()

    def square(self) -> Interval:
        """Exact square (no dependency problem): [0, max^2] when 0 is inside."""
        a, b = np.abs(self.lo), np.abs(self.hi)
        lo = np.where((self.lo <= 0) & (self.hi >= 0), 0.0, np.minimum(a, b) ** 2)
        return Interval(_down(lo).clip(0.0), _up(np.maximum(a, b) ** 2))

    def __pow__(self, p: Any) -> Interval:
        if isinstance(p, Interval):
            if np.all(p.lo == p.hi) and np.ndim(p.lo) == 0:
                p = float(p.lo)
            else:
                return (self.log() * p).exp()
        p = float(p)
        if p == 0:
            return Interval(np.ones_like(self.lo))
        if p == int(p):
            n = int(p)
            if n < 0:
                return (self ** (-n)).reciprocal()
            if n % 2 == 0:
                return self.square() ** (n // 2) if n > 2 else self.square()
            return Interval(_down(self.lo ** n), _up(self.hi ** n))  # odd powers are monotone
        # non-integer powers: defined for x >= 0, monotone increasing for p > 0
        lo = np.clip(self.lo, 0.0, None)
        hi = np.clip(self.hi, 0.0, None)
        if p > 0:
            return Interval(_down(lo ** p), _up(hi ** p))
        with np.errstate(divide="ignore"):
            return Interval(_down(hi ** p), _up(lo ** p))

    def __abs__(self) -> Interval:
        a, b = np.abs(self.lo), np.abs(self.hi)
        lo = np.where((self.lo <= 0) & (self.hi >= 0), 0.0, np.minimum(a, b))
        return Interval(lo, np.maximum(a, b))

    # -- monotone and piecewise functions --------------------------------------------------------
    def sqrt(self) -> Interval:
        return Interval(_down(np.sqrt(np.clip(self.lo, 0, None))).clip(0.0), _up(np.sqrt(np.clip(self.hi, 0, None))))

    def exp(self) -> Interval:
        return Interval(_down(np.exp(self.lo)).clip(0.0), _up(np.exp(self.hi)))

    def log(self) -> Interval:
        with np.errstate(divide="ignore", invalid="ignore"):
            lo = np.where(self.lo > 0, _down(np.log(np.where(self.lo > 0, self.lo, 1.0))), -_INF)
            hi = np.where(self.hi > 0, _up(np.log(np.where(self.hi > 0, self.hi, 1.0))), -_INF)
        return Interval(lo, hi)

    def _periodic(self, f: Any, peaks: float, troughs: float) -> Interval:
        """sin/cos: bounds from the ends plus any extremum (at peaks + 2k pi / troughs + 2k pi) inside."""
        two_pi = 2 * np.pi
        lo_v, hi_v = f(self.lo), f(self.hi)
        lo = np.minimum(lo_v, hi_v)
        hi = np.maximum(lo_v, hi_v)
        has_peak = np.floor((self.hi - peaks) / two_pi) >= np.ceil((self.lo - peaks) / two_pi)
        has_trough = np.floor((self.hi - troughs) / two_pi) >= np.ceil((self.lo - troughs) / two_pi)
        wide = (self.hi - self.lo) >= two_pi
        hi = np.where(has_peak | wide, 1.0, hi)
        lo = np.where(has_trough | wide, -1.0, lo)
        return Interval(_down(lo).clip(-1.0), _up(hi).clip(None, 1.0))

    def sin(self) -> Interval:
        return self._periodic(np.sin, np.pi / 2, -np.pi / 2)

    def cos(self) -> Interval:
        return self._periodic(np.cos, 0.0, np.pi)

    def minimum(self, other: Any) -> Interval:
        o = Interval.of(other)
        return Interval(np.minimum(self.lo, o.lo), np.minimum(self.hi, o.hi))

    def maximum(self, other: Any) -> Interval:
        o = Interval.of(other)
        return Interval(np.maximum(self.lo, o.lo), np.maximum(self.hi, o.hi))

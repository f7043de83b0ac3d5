"""The missing-surface field interface (spec/repair.md §8, from the 2010 paper's "AF").

A field answers, at a point X, given the direction t the normal must be perpendicular to (the
boundary tangent at an origin, the line's tangent elsewhere) and a hint for the normal's sign:
potential Psi (how likely the missing surface passes there), force F, normal N; the attraction
index Omega also needs the outward direction b at a boundary point. A field may provide only some
of these (``provides``); where Psi = 0, F, Omega and N vanish.

- `Biaf`: the boundary indicator field of §4 (indicator.IndicatorField): H at X, N = top
  eigenvector of P H^T H P (16), F = H N, Psi = |H N| = max over admissible n of |H n|.
- `Praf`: the free-point field: Psi_P = sum_i G(|X - P_i|), N_P = the smallest principal axis of
  the free points near X (spec §8 choice); no force.
- `Composite`: a weighted sum; each index is the weighted sum over the fields providing it (the
  normal summed after aligning signs with the hint, then made perpendicular to t and unit). Every
  index must be provided by some member.

The tracers (force_lines.py) use only `sample` and `potential`, so a new field plugs in by
implementing this protocol.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .free_points import FreePoints, praf_normal, praf_potential
from .indicator import IndicatorField

Arr = NDArray[np.float64]
INDICES = frozenset({"potential", "force", "normal", "attraction"})


@dataclass(frozen=True)
class FieldSample:
    """What a field says at one point (None: not provided by this field)."""

    potential: float | None
    force: Arr | None
    normal: Arr | None

    @property
    def tension(self) -> float:
        """Scalar tension |F| (spec §4)."""
        return float(np.linalg.norm(self.force)) if self.force is not None else 0.0


@runtime_checkable
class MissingSurfaceField(Protocol):
    provides: frozenset[str]

    def sample(self, x: Arr, tangent: Arr, hint: Arr) -> FieldSample: ...

    def potential(self, x: Arr, tangent: Arr) -> float: ...

    def attraction(self, x: Arr, tangent: Arr, hint: Arr, outward: Arr) -> float: ...


def _perp_unit(n: Arr, t: Arr) -> Arr:
    tt = t / max(float(np.linalg.norm(t)), 1e-300)
    n = n - (n @ tt) * tt
    return n / max(float(np.linalg.norm(n)), 1e-300)


class Biaf:
    """BIAF: the boundary indicator field (§4) through the protocol."""

    provides = INDICES

    def __init__(self, field: IndicatorField) -> None:
        self.field = field

    def sample(self, x: Arr, tangent: Arr, hint: Arr) -> FieldSample:
        n, f, ten = self.field.sample_one(x, tangent, hint)  # (16a)/(16b), (11) f = H n
        return FieldSample(ten, f, n)

    def potential(self, x: Arr, tangent: Arr) -> float:
        return self.field.sample_one(x, tangent, np.zeros(3))[2]

    def attraction(self, x: Arr, tangent: Arr, hint: Arr, outward: Arr) -> float:
        s = self.sample(x, tangent, hint)
        return s.tension if s.force is not None and float(s.force @ outward) > 0 else 0.0


class Praf:
    """PRAF: the field of the free points (potential and normal only)."""

    provides = frozenset({"potential", "normal"})

    def __init__(self, free: FreePoints) -> None:
        self.free = free

    def sample(self, x: Arr, tangent: Arr, hint: Arr) -> FieldSample:
        psi = float(praf_potential(self.free, x)[0])
        n = praf_normal(self.free, x) if psi > 0 else None
        if n is not None:
            n = _perp_unit(n, np.asarray(tangent, dtype=np.float64))
            if n @ hint < 0:
                n = -n
        return FieldSample(psi, None, n)

    def potential(self, x: Arr, tangent: Arr) -> float:
        return float(praf_potential(self.free, x)[0])

    def attraction(self, x: Arr, tangent: Arr, hint: Arr, outward: Arr) -> float:
        return 0.0


class Composite:
    """Weighted sum of fields; every index must come from at least one member."""

    def __init__(self, members: Sequence[tuple[float, MissingSurfaceField]]) -> None:
        if not members:
            raise ValueError("a composite field needs at least one member")
        for w, _ in members:
            if not w >= 0:
                raise ValueError(f"composite weights must be >= 0, not {w}")
        self.members = list(members)
        have = frozenset().union(*(f.provides for _, f in members))
        missing = INDICES - have
        if missing:
            raise ValueError(f"no member of the composite field provides {', '.join(sorted(missing))}")
        self.provides = have

    def sample(self, x: Arr, tangent: Arr, hint: Arr) -> FieldSample:
        psi, f, n = 0.0, np.zeros(3), np.zeros(3)
        hint = np.asarray(hint, dtype=np.float64)
        for w, fld in self.members:
            s = fld.sample(x, tangent, hint)
            if s.potential is not None:
                psi += w * s.potential
            if s.force is not None:
                f += w * s.force
            if s.normal is not None:
                n += w * (s.normal if s.normal @ hint >= 0 else -s.normal)
        return FieldSample(psi, f, _perp_unit(n, np.asarray(tangent, dtype=np.float64)) if n.any() else None)

    def potential(self, x: Arr, tangent: Arr) -> float:
        return float(sum(w * fld.potential(x, tangent) for w, fld in self.members if "potential" in fld.provides))

    def attraction(self, x: Arr, tangent: Arr, hint: Arr, outward: Arr) -> float:
        return float(sum(w * fld.attraction(x, tangent, hint, outward) for w, fld in self.members
                         if "attraction" in fld.provides))

"""Functionally defined objects: F(x, y, z) >= 0 inside (spec/frep.md §1).

An object is a :class:`FRepObject`: a numeric function, its interval extension (so a box can be
proven outside: the upper bound of F over the box is < 0), the box it lives in (the paper's unit
cube, mapped to ``bounds``) and a gradient (finite differences unless given; needed only by the
error metrics and for orienting faces).

Objects are written in the shared safe expression language (:mod:`algorithms.expr`) with these
building blocks, each with its interval form:

* functions of perturbation: ``F = Q0 + sum_i f_i * pos3(Q_i)`` with ``pos3(q) = q^3`` where
  ``q >= 0`` and 0 elsewhere (the cubic-support perturbation R_i = Q_i^3 of spec §1), each Q_i
  a quadric, e.g. ``1 - ((x-cx)/a)**2 - ((y-cy)/b)**2 - ((z-cz)/c)**2``;
* R-functions (spec/hybrid.md (3)): ``r_and(a, b) = a + b - sqrt(a^2 + b^2)``,
  ``r_or(a, b) = a + b + sqrt(a^2 + b^2)``, ``r_not(a) = -a``;
* plain implicits: sphere, torus, blobs through ``sqrt``/``exp``/polynomials.

Spec files (JSON): ``{"name", "description", "bounds": [[x0,y0,z0],[x1,y1,z1]], "defs": {name:
expression, ...}, "F": expression, "closed": bool, "genus": int}``; ``defs`` are compiled in
order and may use the earlier ones.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..expr import ExpressionError, Function, compile_defs, compile_expr
from ..io import InputError
from .interval import Interval


# -- building blocks with numeric and interval forms --------------------------------------------
def _pos3(q: Any) -> Any:
    """R_i = Q_i^3 where Q_i >= 0, else 0 (spec §1)."""
    return np.maximum(q, 0.0) ** 3


def _pos3_iv(q: Interval) -> Interval:
    q = Interval.of(q)  # monotone non-decreasing: the bounds map to the bounds
    return Interval(np.maximum(q.lo, 0.0) ** 3 * (1 - 4e-16), np.maximum(q.hi, 0.0) ** 3 * (1 + 4e-16))


def _r_and(a: Any, b: Any) -> Any:
    return a + b - np.sqrt(a * a + b * b)  # hybrid.md (3)


def _r_or(a: Any, b: Any) -> Any:
    return a + b + np.sqrt(a * a + b * b)  # hybrid.md (3)


def _r_and_iv(a: Any, b: Any) -> Interval:
    a, b = Interval.of(a), Interval.of(b)
    # a + b - sqrt(a^2 + b^2) is non-decreasing in a and in b (d/da = 1 - a/|(a,b)| >= 0):
    # the bounds are the values at the corners (lo, lo) and (hi, hi); exact, no dependency.
    lo = _r_and(a.lo, b.lo)
    hi = _r_and(a.hi, b.hi)
    return Interval(np.nextafter(lo - 1e-15 * np.abs(lo), -np.inf), np.nextafter(hi + 1e-15 * np.abs(hi), np.inf))


def _r_or_iv(a: Any, b: Any) -> Interval:
    a, b = Interval.of(a), Interval.of(b)
    lo = _r_or(a.lo, b.lo)  # also non-decreasing in both arguments
    hi = _r_or(a.hi, b.hi)
    return Interval(np.nextafter(lo - 1e-15 * np.abs(lo), -np.inf), np.nextafter(hi + 1e-15 * np.abs(hi), np.inf))


FUNCTIONS: dict[str, Function] = {
    "pos3": Function(_pos3, _pos3_iv, 1, "q^3 where q >= 0, else 0: the cubic-support perturbation"),
    "r_and": Function(_r_and, _r_and_iv, 2, "R-conjunction a + b - sqrt(a^2 + b^2)"),
    "r_or": Function(_r_or, _r_or_iv, 2, "R-disjunction a + b + sqrt(a^2 + b^2)"),
    "r_not": Function(lambda a: -a, lambda a: -a, 1, "R-negation -a"),
}


@dataclass(frozen=True, eq=False)
class FRepObject:
    """F(p) >= 0 inside. ``value`` takes (N, 3) points; ``interval`` takes three Intervals."""

    name: str
    numeric: Callable[[Any, Any, Any], Any] = field(repr=False)
    interval_form: Callable[[Any, Any, Any], Interval] = field(repr=False)
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]] = ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    description: str = ""
    closed: bool = True
    genus: int | None = None
    text: str = ""
    grad: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        lo, hi = np.asarray(self.bounds[0], float), np.asarray(self.bounds[1], float)
        if lo.shape != (3,) or hi.shape != (3,) or not np.all(hi > lo):
            raise ValueError(f"bounds: need [[x0,y0,z0],[x1,y1,z1]] with x1>x0 etc., got {self.bounds}")

    @property
    def lo(self) -> NDArray[np.float64]:
        return np.asarray(self.bounds[0], dtype=np.float64)

    @property
    def size(self) -> NDArray[np.float64]:
        return np.asarray(self.bounds[1], dtype=np.float64) - self.lo

    def value(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        p = np.asarray(points, dtype=np.float64)
        out = self.numeric(p[..., 0], p[..., 1], p[..., 2])
        return np.broadcast_to(np.asarray(out, dtype=np.float64), p.shape[:-1]).copy()

    def interval(self, x: Interval, y: Interval, z: Interval) -> Interval:
        """Enclosure of F over the boxes x × y × z (element-wise)."""
        out = Interval.of(self.interval_form(x, y, z))
        shape = np.broadcast_shapes(np.shape(x.lo), np.shape(y.lo), np.shape(z.lo))
        return Interval(np.broadcast_to(out.lo, shape), np.broadcast_to(out.hi, shape))

    def gradient(self, points: NDArray[np.float64], *, h: float | None = None) -> NDArray[np.float64]:
        """(N, 3) gradient: the analytic one if given, else central differences with step h."""
        p = np.asarray(points, dtype=np.float64)
        if self.grad is not None:
            return np.asarray(self.grad(p), dtype=np.float64)
        h = float(h if h is not None else 1e-6 * float(self.size.max()))
        g = np.empty(p.shape)
        for k in range(3):  # three axes
            d = np.zeros(3)
            d[k] = h
            g[..., k] = (self.value(p + d) - self.value(p - d)) / (2 * h)
        return g


def from_expression(text: str, *, defs: Mapping[str, str] | None = None, name: str = "object",
                    bounds: Any = ((-1, -1, -1), (1, 1, 1)), description: str = "", closed: bool = True,
                    genus: int | None = None) -> FRepObject:
    """Compile F (and its definitions) with the shared expression language and our building blocks."""
    try:
        named = compile_defs(dict(defs or {}), functions=FUNCTIONS)
        expr = compile_expr(text, functions=FUNCTIONS, names=named)
    except ExpressionError as exc:
        raise InputError(f"{name}: {exc}") from None

    def numeric(x: Any, y: Any, z: Any) -> Any:
        return expr(x=x, y=y, z=z)

    def interval(x: Interval, y: Interval, z: Interval) -> Interval:
        return Interval.of(expr.interval(x=x, y=y, z=z))

    b = tuple(tuple(float(c) for c in row) for row in bounds)
    return FRepObject(name, numeric, interval, b, description, closed, genus, text)  # type: ignore[arg-type]


def load_spec(path: str | Path) -> FRepObject:
    """Read a JSON spec file (see the module docstring)."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not valid JSON ({exc})") from None
    return spec_object(data, source=str(path))


def spec_object(data: Mapping[str, Any], *, source: str = "spec") -> FRepObject:
    if not isinstance(data, Mapping) or "F" not in data:
        raise InputError(f"{source}: a spec needs the key 'F' (the function, >= 0 inside)")
    unknown = set(data) - {"name", "description", "bounds", "defs", "F", "closed", "genus", "kind"}
    if unknown:
        raise InputError(f"{source}: unknown keys {sorted(unknown)}")
    try:
        return from_expression(str(data["F"]), defs=data.get("defs"), name=str(data.get("name", source)),
                               bounds=data.get("bounds", ((-1, -1, -1), (1, 1, 1))),
                               description=str(data.get("description", "")), closed=bool(data.get("closed", True)),
                               genus=data.get("genus"))
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from None


# -- the bundled objects as Python constructors (texts in the same language) ----------------------
def sphere(radius: float = 0.8, center: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> FRepObject:
    cx, cy, cz = center
    return from_expression(f"{radius}**2 - (x-{cx})**2 - (y-{cy})**2 - (z-{cz})**2", name="sphere",
                           closed=True, genus=0)


def torus(major: float = 0.6, minor: float = 0.25) -> FRepObject:
    return from_expression(f"{minor}**2 - (sqrt(x**2 + y**2) - {major})**2 - z**2", name="torus",
                           closed=True, genus=1)


def blobs(centers: Any = ((-0.35, 0.0, 0.0), (0.35, 0.05, 0.0), (0.0, 0.3, 0.2)),
          strength: float = 6.0, threshold: float = 0.45) -> FRepObject:
    terms = " + ".join(f"exp(-{strength}*((x-{c[0]})**2 + (y-{c[1]})**2 + (z-{c[2]})**2))" for c in centers)
    return from_expression(f"{terms} - {threshold}", name="blob", closed=True, genus=0)


def perturbed(base: tuple[float, float, float] = (0.75, 0.6, 0.5),
              bumps: Any = ((0.5, (0.55, 0.0, 0.3), (0.3, 0.3, 0.3)),
                            (0.6, (-0.4, 0.3, 0.2), (0.25, 0.25, 0.35)),
                            (-0.5, (0.0, -0.3, 0.4), (0.3, 0.25, 0.25)))) -> FRepObject:
    """Q0 an ellipsoid with semi-axes ``base``; bumps (f_i, centre, semi-axes) added as f_i * Q_i^3."""
    a, b, c = base
    q0 = f"1 - (x/{a})**2 - (y/{b})**2 - (z/{c})**2"
    terms = [f"{f} * pos3(1 - ((x-{cc[0]})/{r[0]})**2 - ((y-{cc[1]})/{r[1]})**2 - ((z-{cc[2]})/{r[2]})**2)"
             for f, cc, r in bumps]
    return from_expression(" + ".join([q0, *terms]), name="perturbed", closed=True, genus=0)


def demo_object(name: str) -> FRepObject:
    """A bundled object by demo name (assets/frep/index.json)."""
    from ..demos import demo

    return load_spec(demo(name, "frep").path)

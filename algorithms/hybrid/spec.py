"""Surface spec files: a parametric surface, its trim and default mesh parameters, as JSON.

Every formula is text in the safe expression language of :mod:`algorithms.expr` (parsed with
``ast`` against a whitelist, never given to ``eval``), extended with the R-functions.

    {
      "name": "bezier-hole",
      "description": "...",
      "constants": {"r": 0.4},                   # named numbers (or constant expressions)
      "surface": {"type": "bezier", "control": [[[x, y, z], ...], ...]},
      "defs": {"x1": "rot_x(x, z, a1)"},         # named sub-expressions of x, y, z
      "trim": "y**2 + z**2 - r**2",              # F(x, y, z) > 0 on the kept part
      "mesh": {"max_edge": 0.1, "min_angle": 30}  # HybridParams defaults
    }

Surface types: bezier (control (n+1, m+1, 3)), cone (r1, r2, length, v0), cylinder (radius, z0,
z1, v0), sphere (radius, lat0, lat1, lon0, lon1), torus (major, minor, u0, v0), expression (x, y,
z: text in u, v; domain [a, b, c, d]; periodic_u, periodic_v). Numbers may be constant expressions.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..expr import ExpressionError, compile_defs, compile_expr
from ..io import InputError
from . import surfaces as S
from .mesher import HybridParams
from .model import HybridModel
from .rfunctions import EXPR_FUNCTIONS


@dataclass(frozen=True)
class Spec:
    model: HybridModel
    mesh: dict[str, Any] = field(default_factory=dict)
    source: str = ""

    def params(self, **overrides: Any) -> HybridParams:
        base = {k: v for k, v in self.mesh.items() if k in HybridParams.__dataclass_fields__}
        base.update({k: v for k, v in overrides.items() if v is not None})
        return HybridParams(**base)


def _number(x: Any, consts: Mapping[str, float], what: str) -> float:
    if isinstance(x, bool):
        raise InputError(f"{what}: expected a number, got {x!r}")
    if isinstance(x, (int, float)):
        return float(x)
    if isinstance(x, str):
        e = compile_expr(x, variables=(), constants=consts)
        return float(e())
    raise InputError(f"{what}: expected a number, got {x!r}")


def _surface(d: Mapping[str, Any], consts: Mapping[str, float], name: str) -> S.Surface:
    if not isinstance(d, Mapping) or "type" not in d:
        raise InputError("surface: an object with a 'type' is required")
    kind = d["type"]

    def num(key: str, default: float | None = None) -> float:
        if key not in d:
            if default is None:
                raise InputError(f"surface.{key}: missing (needed by type {kind!r})")
            return default
        return _number(d[key], consts, f"surface.{key}")

    if kind == "bezier":
        try:
            ctrl = [[[_number(c, consts, "surface.control") for c in p] for p in row] for row in d["control"]]
            return S.bezier(ctrl, name=name)
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"surface.control: {exc}") from None
    if kind == "cone":
        return S.cone(num("r1"), num("r2"), num("length"), v0=num("v0", 0.0), name=name)
    if kind == "cylinder":
        return S.cylinder(num("radius"), num("z0"), num("z1"), v0=num("v0", 0.0), name=name)
    if kind == "sphere":
        return S.sphere(num("radius"), num("lat0"), num("lat1"), lon0=num("lon0", 0.0),
                        lon1=num("lon1", 6.283185307179586), name=name)
    if kind == "torus":
        return S.torus(num("major"), num("minor"), u0=num("u0", 0.0), v0=num("v0", 0.0), name=name)
    if kind == "expression":
        fx, fy, fz = (compile_expr(str(d[k]), variables=("u", "v"), constants=consts) for k in ("x", "y", "z"))
        dom = d.get("domain")
        if not isinstance(dom, list) or len(dom) != 4:
            raise InputError("surface.domain: [a, b, c, d] required for an expression surface")
        return S.from_functions(lambda u, v: fx(u=u, v=v), lambda u, v: fy(u=u, v=v), lambda u, v: fz(u=u, v=v),
                                tuple(_number(x, consts, "surface.domain") for x in dom),
                                periodic_u=bool(d.get("periodic_u", False)),
                                periodic_v=bool(d.get("periodic_v", False)), name=name)
    raise InputError(f"surface.type: unknown {kind!r} (bezier, cone, cylinder, sphere, torus, expression)")


def spec_from_dict(data: Mapping[str, Any], *, source: str = "") -> Spec:
    """Build a model from a parsed spec (errors name the offending field)."""
    if not isinstance(data, Mapping):
        raise InputError("a spec must be a JSON object")
    name = str(data.get("name", "surface"))
    try:
        consts: dict[str, float] = {}
        for k, v in dict(data.get("constants", {})).items():
            if not str(k).isidentifier():
                raise InputError(f"constants: {k!r} is not a name")
            consts[k] = _number(v, consts, f"constants.{k}")
        surf = _surface(data.get("surface"), consts, name)  # type: ignore[arg-type]
        trim = None
        if data.get("trim") is not None:
            defs = compile_defs(dict(data.get("defs", {})), variables=("x", "y", "z"),
                                functions=EXPR_FUNCTIONS, constants=consts)
            F = compile_expr(str(data["trim"]), variables=("x", "y", "z"), functions=EXPR_FUNCTIONS,
                             constants=consts, names=defs)

            def trim(x: Any, y: Any, z: Any) -> Any:
                return F(x=x, y=y, z=z)
    except ExpressionError as exc:
        raise InputError(f"{source or name}: {exc}") from None
    mesh = dict(data.get("mesh", {}))
    unknown = set(mesh) - set(HybridParams.__dataclass_fields__)
    if unknown:
        raise InputError(f"mesh: unknown parameter(s) {', '.join(sorted(unknown))}")
    model = HybridModel(name, surf, trim, str(data.get("description", "")))
    return Spec(model, mesh, source)


def load_spec(path: str | Path) -> Spec:
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such file")
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not valid JSON ({exc})") from None
    return spec_from_dict(data, source=str(path))

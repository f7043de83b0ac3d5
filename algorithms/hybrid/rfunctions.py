"""Rvachev R-functions for trimming (spec/hybrid.md §1, the paper's eq. (2), (3)).

Every function works on floats and numpy arrays. Sign convention: a function is > 0 inside
the region it describes, = 0 on its border, < 0 outside. The R-operations of system (3)
keep that convention: sign(x ∧ y) = sign(min(x, y)), sign(x ∨ y) = sign(max(x, y)).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..expr import Function


def r_not(x: Any) -> Any:
    """¬x ≡ −x  (3)."""
    return -x


def r_and(x: Any, *ys: Any) -> Any:
    """x ∧ y ≡ x + y − √(x² + y²)  (3); n-ary, folded from the left."""
    out = x
    for y in ys:
        out = out + y - np.hypot(out, y)  # hypot: √(x² + y²) in one pass, no overflow
    return out


def r_or(x: Any, *ys: Any) -> Any:
    """x ∨ y ≡ x + y + √(x² + y²)  (3); n-ary, folded from the left."""
    out = x
    for y in ys:
        out = out + y + np.hypot(out, y)
    return out


def circle_z(x: Any, y: Any, r: Any) -> Any:
    """r² − x² − y²  (2): a disk in the plane, an infinite cylinder along Oz in space."""
    return r * r - x * x - y * y


def rect(x: Any, y: Any, w: Any, h: Any) -> Any:
    """A w × h rectangle centred at the origin: (w²/4 − x²) ∧ (h²/4 − y²)."""
    return r_and(w * w / 4 - x * x, h * h / 4 - y * y)


def srect(x: Any, y: Any, w: Any, h: Any, r: Any) -> Any:
    """A w × h rectangle with its corners rounded by r: two crossed rectangles ∨ four corner disks."""
    cx, cy = w / 2 - r, h / 2 - r
    return r_or(rect(x, y, w - 2 * r, h), rect(x, y, w, h - 2 * r),
                circle_z(x - cx, y - cy, r), circle_z(x + cx, y - cy, r),
                circle_z(x - cx, y + cy, r), circle_z(x + cx, y + cy, r))


def rot_x(x: Any, z: Any, alpha: Any) -> Any:
    """x_i = x cos α + z sin α: the x coordinate after rotating by α about the Oy axis (§5)."""
    return x * np.cos(alpha) + z * np.sin(alpha)


def rot_z(x: Any, z: Any, alpha: Any) -> Any:
    """z_i = −x sin α + z cos α: the z coordinate after rotating by α about the Oy axis (§5)."""
    return -x * np.sin(alpha) + z * np.cos(alpha)


def crossing_cylinders(x: Any, y: Any, z: Any, rx: Any, ry: Any) -> Any:
    """f1 = −[(r_x² − y² − z²) ∨ (r_y² − x² − z²)]: positive outside two crossing cylinders (along Ox, Oy)."""
    return -r_or(rx * rx - y * y - z * z, ry * ry - x * x - z * z)


# The R-functions as functions of the safe expression language (algorithms/expr.py).
EXPR_FUNCTIONS: dict[str, Function] = {
    "r_not": Function(r_not, None, 1, "¬x = −x"),
    "r_and": Function(r_and, None, None, "x ∧ y = x + y − sqrt(x² + y²)"),
    "r_or": Function(r_or, None, None, "x ∨ y = x + y + sqrt(x² + y²)"),
    "circle_z": Function(circle_z, None, 3, "r² − x² − y²"),
    "rect": Function(rect, None, 4, "w × h rectangle"),
    "srect": Function(srect, None, 5, "w × h rectangle, corners rounded by r"),
    "rot_x": Function(rot_x, None, 3, "x cos a + z sin a"),
    "rot_z": Function(rot_z, None, 3, "−x sin a + z cos a"),
    "crossing_cylinders": Function(crossing_cylinders, None, 5, "f1: outside two crossing cylinders"),
}

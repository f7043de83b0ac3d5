"""The geometric tests on the surface (spec/hybrid.md §4, Fig. 3, eq. (6)).

Scalar functions on 3-tuples (the refinement calls them one triangle at a time, so plain
floats and ``math`` are much faster than numpy scalars here).
"""

from __future__ import annotations

import math

Vec = tuple[float, float, float]


def local_frame(A: Vec, B: Vec, C: Vec) -> tuple[Vec, Vec, Vec] | None:
    """The rows of Λ (6): x′ along A3B3, z′ along the triangle normal, y′ = z′ × x′.
    None for a degenerate triangle."""
    bx, by, bz = B[0] - A[0], B[1] - A[1], B[2] - A[2]
    cx, cy, cz = C[0] - A[0], C[1] - A[1], C[2] - A[2]
    nx, ny, nz = by * cz - bz * cy, bz * cx - bx * cz, bx * cy - by * cx
    lb = math.sqrt(bx * bx + by * by + bz * bz)
    ln = math.sqrt(nx * nx + ny * ny + nz * nz)
    if lb == 0.0 or ln <= 1e-300 or ln <= 1e-15 * lb * math.sqrt(cx * cx + cy * cy + cz * cz):
        return None
    x = (bx / lb, by / lb, bz / lb)
    z = (nx / ln, ny / ln, nz / ln)
    y = (z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0])
    return x, y, z


def to_local(frame: tuple[Vec, Vec, Vec], A: Vec, P: Vec) -> Vec:
    """P3′ = Λ (P3 − A3)."""
    d = (P[0] - A[0], P[1] - A[1], P[2] - A[2])
    return tuple(r[0] * d[0] + r[1] * d[1] + r[2] * d[2] for r in frame)  # type: ignore[return-value]


def circumcircle_2d(bx: float, cx: float, cy: float) -> tuple[float, float, float]:
    """Circumcentre and squared radius of A′ = (0, 0), B′ = (bx, 0), C′ = (cx, cy)."""
    ex = 0.5 * bx
    ey = (cx * cx + cy * cy - bx * cx) / (2.0 * cy)
    return ex, ey, ex * ex + ey * ey


def circumcentre_3d(A: Vec, B: Vec, C: Vec) -> Vec | None:
    """E3 = A3 + Λᵀ E3′: the circumcentre of the 3D triangle, through the local frame (§4)."""
    fr = local_frame(A, B, C)
    if fr is None:
        return None
    bl = to_local(fr, A, B)
    cl = to_local(fr, A, C)
    ex, ey, _ = circumcircle_2d(bl[0], cl[0], cl[1])
    x, y, _z = fr
    return (A[0] + x[0] * ex + y[0] * ey, A[1] + x[1] * ex + y[1] * ey, A[2] + x[2] * ex + y[2] * ey)


def incircle_3d(A: Vec, B: Vec, C: Vec, P: Vec, l: float) -> bool:
    """Fig. 3: is P3 inside the cylinder of height 2l over the circumcircle of A3 B3 C3?

    P's local coordinates (x′, y′) must lie inside the circumcircle of A3′ B3′ C3′ and
    −l ≤ z′_P ≤ l, where l is the deviation of the surface from the triangle's plane.
    """
    fr = local_frame(A, B, C)
    if fr is None:
        return False
    bl = to_local(fr, A, B)
    cl = to_local(fr, A, C)
    pl = to_local(fr, A, P)
    ex, ey, r2 = circumcircle_2d(bl[0], cl[0], cl[1])
    dx, dy = pl[0] - ex, pl[1] - ey
    return dx * dx + dy * dy < r2 * (1.0 - 1e-12) and -l <= pl[2] <= l


def incircle_2d(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float],
                p: tuple[float, float]) -> bool:
    """The ordinary in-circle test in the plane (a, b, c counter-clockwise)."""
    adx, ady = a[0] - p[0], a[1] - p[1]
    bdx, bdy = b[0] - p[0], b[1] - p[1]
    cdx, cdy = c[0] - p[0], c[1] - p[1]
    ad, bd, cd = adx * adx + ady * ady, bdx * bdx + bdy * bdy, cdx * cdx + cdy * cdy
    det = adx * (bdy * cd - bd * cdy) - ady * (bdx * cd - bd * cdx) + ad * (bdx * cdy - bdy * cdx)
    scale = (abs(adx) + abs(bdx) + abs(cdx) + abs(ady) + abs(bdy) + abs(cdy)) ** 4
    return det > 1e-13 * scale


def orient(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float]) -> float:
    """Twice the signed area of (a, b, c): > 0 counter-clockwise."""
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def min_angle_3d(A: Vec, B: Vec, C: Vec) -> tuple[float, int]:
    """(smallest angle in degrees, index of its vertex 0/1/2) of a 3D triangle."""
    la = (B[0] - C[0]) ** 2 + (B[1] - C[1]) ** 2 + (B[2] - C[2]) ** 2  # opposite A
    lb = (A[0] - C[0]) ** 2 + (A[1] - C[1]) ** 2 + (A[2] - C[2]) ** 2
    lc = (A[0] - B[0]) ** 2 + (A[1] - B[1]) ** 2 + (A[2] - B[2]) ** 2
    if la <= lb and la <= lc:
        k, opp, s1, s2 = 0, la, lb, lc
    elif lb <= lc:
        k, opp, s1, s2 = 1, lb, la, lc
    else:
        k, opp, s1, s2 = 2, lc, la, lb
    den = 2.0 * math.sqrt(s1 * s2)
    if den == 0.0:
        return 0.0, k
    cosv = max(-1.0, min(1.0, (s1 + s2 - opp) / den))
    return math.degrees(math.acos(cosv)), k

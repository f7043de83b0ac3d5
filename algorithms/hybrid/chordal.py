"""The chordal error of mesh triangles against the surface: the curvature criterion in absolute form.

For each triangle, the points checked are its three edge midpoints and its centroid (in space); each
is compared with the surface near it: the same barycentric point in (u, v) mapped by R, moved by one
Gauss-Newton step of min |R(u, v) − point|² (the Jacobian by finite differences), so a
non-uniform parameterisation (a point of R displaced along the surface) does not count as error.
The error is the largest distance found. For an arc of curvature κ a chord of length h deviates by
κh²/8, so bounding this error sizes the mesh h ∝ 1/√κ and spreads the chordal error evenly.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def gauss_newton_step(ru: NDArray[np.float64], rv: NDArray[np.float64],
                      r: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One Gauss-Newton step of min |R(u, v) - target|^2 for many points at once: (du, dv) solving
    the 2x2 normal equations J^T J d = J^T r with J = [ru rv] (..., 3) and r = target - R(u, v);
    (0, 0) where J^T J is singular. The surface circumcentre (eq. 7), the chordal error and
    smoothing's moves on the surface all take this step."""
    a11, a12, a22 = (ru * ru).sum(-1), (ru * rv).sum(-1), (rv * rv).sum(-1)
    g1, g2 = (ru * r).sum(-1), (rv * r).sum(-1)
    det = a11 * a22 - a12 * a12
    ok = det > 0
    det = np.where(ok, det, 1.0)
    return np.where(ok, (a22 * g1 - a12 * g2) / det, 0.0), np.where(ok, (a11 * g2 - a12 * g1) / det, 0.0)


def chordal_errors(surface, T3: NDArray[np.float64], T2: NDArray[np.float64]) -> NDArray[np.float64]:
    """(K,) chordal error of triangles T3 (K, 3, 3) whose vertices have parameters T2 (K, 3, 2)."""
    return sample_errors(surface, T3, T2).max(axis=1) if len(T3) else np.zeros(0)


def sample_errors(surface, T3: NDArray[np.float64], T2: NDArray[np.float64]) -> NDArray[np.float64]:
    """(K, 4) the distances at the midpoints of edges (0, 1), (1, 2), (2, 0) and at the centroid."""
    S3 = np.concatenate([0.5 * (T3 + T3[:, [1, 2, 0]]), T3.mean(axis=1, keepdims=True)], axis=1)  # (K, 4, 3)
    S2 = np.concatenate([0.5 * (T2 + T2[:, [1, 2, 0]]), T2.mean(axis=1, keepdims=True)], axis=1)
    a, b, c, d = surface.domain
    hu, hv = 1e-7 * (b - a), 1e-7 * (d - c)
    u, v = S2[..., 0], S2[..., 1]
    q = surface(np.stack([u, u + hu, u]), np.stack([v, v, v + hv]))  # one call: R and its derivatives
    R = q[0]
    ru, rv = (q[1] - R) / hu, (q[2] - R) / hv
    r = S3 - R
    du, dv = gauss_newton_step(ru, rv, r)
    R2 = surface(np.clip(u + du, a, b), np.clip(v + dv, c, d))
    dist = np.minimum(np.sqrt(((R2 - S3) ** 2).sum(-1)), np.sqrt((r * r).sum(-1)))
    return dist


def chord_arc_ratios(surface, uv: NDArray[np.float64], ends: NDArray[np.float64]) -> NDArray[np.float64]:
    """(K,) chord / arc of edges with parameters uv (K, 2, 2) and end points ends (K, 2, 3): the arc
    is the polyline through the surface at 1/4, 1/2, 3/4 of the parameter segment (one surface call);
    1 for a zero-length arc. The curvature criterion in its ratio form (spec/hybrid.md §4)."""
    s = np.array([0.25, 0.5, 0.75])[None, :, None]
    mid = uv[:, :1] + s * (uv[:, 1:] - uv[:, :1])  # (K, 3, 2)
    q = surface(mid[..., 0], mid[..., 1])  # (K, 3, 3)
    pts = np.concatenate([ends[:, :1], q, ends[:, 1:]], axis=1)
    seg = np.diff(pts, axis=1)
    arc = np.sqrt((seg * seg).sum(-1)).sum(-1)
    d = ends[:, 1] - ends[:, 0]
    chord = np.sqrt((d * d).sum(-1))
    return np.where(arc > 0, chord / np.where(arc > 0, arc, 1.0), 1.0)

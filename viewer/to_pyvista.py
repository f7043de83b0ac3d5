"""The only place that turns algorithm data into pyvista objects."""

from __future__ import annotations

import numpy as np
import pyvista as pv
from numpy.typing import NDArray

from algorithms.mesh import Mesh


def polydata(mesh: Mesh | tuple[NDArray, NDArray]) -> pv.PolyData:
    v, f = (mesh.vertices, mesh.faces) if isinstance(mesh, Mesh) else mesh
    cells = np.hstack([np.full((len(f), 1), 3), np.asarray(f)]).ravel() if len(f) else np.zeros(0, dtype=np.int64)
    return pv.PolyData(np.asarray(v, dtype=np.float64), cells)


def polyline(points: NDArray[np.float64], *, closed: bool = False) -> pv.PolyData:
    """One polyline through the points (closed back to the first if asked)."""
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    ids = list(range(n)) + ([0] if closed and n > 2 else [])
    return pv.PolyData(pts, lines=np.array([len(ids), *ids]))


def polylines(chains: list[NDArray[np.float64]], *, closed: bool = False,
              scalars: NDArray | None = None, name: str = "value") -> pv.PolyData:
    """Many polylines in one PolyData (one actor), with an optional per-line scalar."""
    pts, lines, cell_vals = [], [], []
    off = 0
    for k, c in enumerate(chains):
        c = np.asarray(c, dtype=np.float64)
        n = len(c)
        if n < 2:
            continue
        ids = list(range(off, off + n)) + ([off] if closed and n > 2 else [])
        lines += [len(ids), *ids]
        pts.append(c)
        off += n
        if scalars is not None:
            cell_vals.append(scalars[k])
    if not pts:
        return pv.PolyData()
    pd = pv.PolyData(np.vstack(pts), lines=np.array(lines))
    if scalars is not None:
        pd.cell_data[name] = np.asarray(cell_vals, dtype=np.float64)
    return pd


def points(p: NDArray[np.float64]) -> pv.PolyData:
    return pv.PolyData(np.asarray(p, dtype=np.float64).reshape(-1, 3))


def surface(vertices: NDArray[np.float64], faces: NDArray[np.int64], *,
            cell_data: dict[str, NDArray] | None = None) -> pv.PolyData:
    """A triangle surface with per-triangle arrays (e.g. the min angle, a highlight mask)."""
    pd = polydata((np.asarray(vertices), np.asarray(faces)))
    for k, a in (cell_data or {}).items():
        pd.cell_data[k] = np.asarray(a)
    return pd


def polyline_prefix(pts: NDArray[np.float64], k: int, *, out: pv.PolyData | None = None) -> pv.PolyData:
    """A polyline over the first k of the points (all points kept, so it updates in place).

    With ``out``, only the line connectivity of that mesh changes (cheap: the animation's frame).
    """
    pts = np.asarray(pts, dtype=np.float64)
    k = max(1, min(int(k), len(pts)))
    ids = np.arange(k) if k > 1 else np.array([0, 0])
    lines = np.concatenate([[len(ids)], ids])
    if out is None:
        return pv.PolyData(pts.copy(), lines=lines)
    out.lines = lines
    return out


def tubes(chains: list[NDArray[np.float64]], values: NDArray[np.float64], *, radius: float,
          name: str = "value", sides: int = 10) -> pv.PolyData:
    """Tubes around polylines (one tube filter call for all), one scalar per line carried on
    every tube point, and ``line`` = the index of the chain each tube point belongs to (so the
    scalars can be updated in place)."""
    pts, lines, owner, vals = [], [], [], []
    off = 0
    for k, (c, v) in enumerate(zip(chains, values)):
        c = np.asarray(c, dtype=np.float64)
        if len(c) < 2:
            continue
        keep = np.concatenate([[True], np.linalg.norm(np.diff(c, axis=0), axis=1) > 1e-12])
        c = c[keep]  # the tube filter fails on repeated points
        if len(c) < 2:
            continue
        n = len(c)
        pts.append(c)
        lines += [n, *range(off, off + n)]
        owner.append(np.full(n, k, dtype=np.int64))
        vals.append(np.full(n, float(v)))
        off += n
    if not pts:
        return pv.PolyData()
    pd = pv.PolyData(np.vstack(pts), lines=np.asarray(lines))
    pd.point_data[name] = np.concatenate(vals)
    pd.point_data["line"] = np.concatenate(owner)
    t = pd.tube(radius=radius, n_sides=sides, capping=True)
    t.point_data["line"] = np.rint(t.point_data["line"]).astype(np.int64)
    t.set_active_scalars(name)
    return t


_ARROW: pv.PolyData | None = None


def _unit_arrow() -> pv.PolyData:
    global _ARROW
    if _ARROW is None:
        _ARROW = pv.Arrow(start=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0), scale=1.0, tip_length=0.3,
                          tip_radius=0.12, shaft_radius=0.04, tip_resolution=12, shaft_resolution=12)
    return _ARROW


def arrow_points(start: NDArray[np.float64], direction: NDArray[np.float64], length: float) -> NDArray[np.float64]:
    """The points of the unit arrow placed at start along a unit direction (numpy only: cheap per frame)."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / (np.linalg.norm(d) or 1.0)
    helper = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    w = np.cross(d, u)
    p = np.asarray(_unit_arrow().points)
    return np.asarray(start, dtype=np.float64) + float(length) * (p[:, :1] * d + p[:, 1:2] * u + p[:, 2:3] * w)


def arrow(start: NDArray[np.float64], direction: NDArray[np.float64], length: float) -> pv.PolyData:
    """An arrow from start along a direction (same topology every time: update its points in place)."""
    a = _unit_arrow().copy()
    a.points = arrow_points(start, direction, length)
    return a

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

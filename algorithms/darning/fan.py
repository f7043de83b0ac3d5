"""The paper's darning method: a triangle fan around the centroid of the hole's boundary
(spec/repair.md §6 step 4; the weakest method, the paper's costs are worst cases)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def fan(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Fan of a closed loop around the centroid of its points.

    points: (n, 3) the loop in its positive direction (the surrounding surface holds the
    half-edges v_j -> v_{j+1}).
    Returns (centroid (3,), faces (n, 3)) in local indices, the centroid numbered n; face j is
    (v_{j+1}, v_j, c): it holds the loop edge reversed, so it is oriented like the surroundings.
    """
    p = np.asarray(points, dtype=np.float64)
    n = len(p)
    if n < 3:
        raise ValueError(f"a hole needs at least 3 vertices, got {n}")
    j = np.arange(n)
    faces = np.stack([(j + 1) % n, j, np.full(n, n)], axis=1)
    return p.mean(axis=0), faces

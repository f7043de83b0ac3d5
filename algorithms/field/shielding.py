"""Shielding (15): is the open segment X -> O blocked by the existing surface?

delta_XO = 0 when the open segment XO crosses any island triangle not incident to O (nor to X,
when X is a mesh vertex), 1 otherwise. The triangles sit in a bounding-volume hierarchy (BVH,
median split on the longest axis, leaves of <= 4 triangles) built once with numpy and traversed
in numba, so one test costs O(log F) box tests instead of F triangle tests.

The segment-triangle test handles the coplanar case too (a segment lying in a triangle's plane,
as between two coplanar disks, "crosses" the triangle when it overlaps its interior): there the
segment is clipped against the triangle's three edge half-planes (Cyrus-Beck). The parameter
window (EPS_T, 1 - EPS_T) keeps the open segment open: touching at X or O does not block.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray

from ..mesh import Mesh

LEAF = 4
EPS_T = 1e-6  # relative parameter margin: the segment is open at both ends
EPS_PAR = 1e-9  # |n . D| below this (relative) counts as parallel to the triangle's plane
EPS_PLANE = 1e-7  # relative distance to the plane for the coplanar test


@dataclass(frozen=True, eq=False)
class Bvh:
    """BVH over F triangles; K nodes. Arrays are what the numba traversal reads.

    node_min, node_max: (K, 3); node_left, node_right: (K,) child nodes (-1 at leaves);
    node_start, node_count: (K,) slice of the reordered triangles at leaves;
    tri: (F, 3, 3) reordered corner coordinates; tri_vertex: (F, 3) their vertex numbers.
    """

    node_min: NDArray[np.float64]
    node_max: NDArray[np.float64]
    node_left: NDArray[np.int64]
    node_right: NDArray[np.int64]
    node_start: NDArray[np.int64]
    node_count: NDArray[np.int64]
    tri: NDArray[np.float64]
    tri_vertex: NDArray[np.int64]
    scale: float  # bounding-box diagonal (for tolerances)

    @property
    def n_triangles(self) -> int:
        return int(len(self.tri))

    def arrays(self) -> tuple:
        return (self.node_min, self.node_max, self.node_left, self.node_right, self.node_start,
                self.node_count, self.tri, self.tri_vertex)


def build_bvh(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> Bvh:
    """Median-split BVH over the triangles (vertices (V, 3), faces (F, 3)).

    The build loops over nodes in Python (a sequential recursion, O(F log F) numpy work overall).
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    tri = v[f]
    cen = tri.mean(axis=1)
    tmin, tmax = tri.min(axis=1), tri.max(axis=1)
    order = np.arange(len(f))
    nmin, nmax, left, right, start, count = [], [], [], [], [], []

    def new_node(s: int, e: int) -> int:
        idx = order[s:e]
        nmin.append(tmin[idx].min(axis=0) if e > s else np.zeros(3))
        nmax.append(tmax[idx].max(axis=0) if e > s else np.zeros(3))
        left.append(-1)
        right.append(-1)
        start.append(s)
        count.append(e - s)
        return len(nmin) - 1

    root = new_node(0, len(f))
    stack = [(root, 0, len(f))] if len(f) else []
    while stack:  # sequential: each split decides the next
        node, s, e = stack.pop()
        if e - s <= LEAF:
            continue
        idx = order[s:e]
        c = cen[idx]
        axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
        mid = (e - s) // 2
        part = np.argpartition(c[:, axis], mid)
        order[s:e] = idx[part]
        a = new_node(s, s + mid)
        b = new_node(s + mid, e)
        left[node], right[node], count[node] = a, b, 0
        stack.append((a, s, s + mid))
        stack.append((b, s + mid, e))
    scale = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0))) if len(v) else 1.0
    return Bvh(np.array(nmin).reshape(-1, 3), np.array(nmax).reshape(-1, 3), np.array(left, dtype=np.int64),
               np.array(right, dtype=np.int64), np.array(start, dtype=np.int64), np.array(count, dtype=np.int64),
               tri[order].reshape(-1, 3, 3), f[order].reshape(-1, 3), max(scale, 1e-300))


def mesh_bvh(mesh: Mesh) -> Bvh:
    return build_bvh(mesh.vertices, mesh.faces)


@numba.njit(cache=True, fastmath=False)
def _seg_box(x0, x1, x2, d0, d1, d2, bmin, bmax, pad):
    """Does the segment X + t D, t in [0, 1], meet the box padded by pad? (slab test)"""
    t0 = 0.0
    t1 = 1.0
    xs = (x0, x1, x2)
    ds = (d0, d1, d2)
    for k in range(3):
        lo = bmin[k] - pad
        hi = bmax[k] + pad
        xk = xs[k]
        dk = ds[k]
        if abs(dk) < 1e-300:
            if xk < lo or xk > hi:
                return False
        else:
            inv = 1.0 / dk
            ta = (lo - xk) * inv
            tb = (hi - xk) * inv
            if ta > tb:
                ta, tb = tb, ta
            if ta > t0:
                t0 = ta
            if tb < t1:
                t1 = tb
            if t0 > t1:
                return False
    return True


@numba.njit(cache=True)
def _seg_tri(x, d, a, b, c, scale):
    """Does the open segment X + t D, t in (EPS_T, 1 - EPS_T), cross the triangle abc?"""
    e1 = b - a
    e2 = c - a
    n = np.cross(e1, e2)
    nn = np.sqrt(n @ n)
    if nn == 0.0:
        return False
    dl = np.sqrt(d @ d)
    denom = n @ d
    dist0 = n @ (x - a)
    if abs(denom) > EPS_PAR * nn * dl:
        t = -dist0 / denom
        if t <= EPS_T or t >= 1.0 - EPS_T:
            return False
        p = x + t * d - a
        # barycentric coordinates of p in (e1, e2)
        d11 = e1 @ e1
        d12 = e1 @ e2
        d22 = e2 @ e2
        p1 = p @ e1
        p2 = p @ e2
        den = d11 * d22 - d12 * d12
        u = (d22 * p1 - d12 * p2) / den
        v = (d11 * p2 - d12 * p1) / den
        return u >= 0.0 and v >= 0.0 and u + v <= 1.0
    # parallel: only a segment lying in the plane can cross (Cyrus-Beck clip against the edges)
    if abs(dist0) > EPS_PLANE * nn * scale:
        return False
    t0 = EPS_T
    t1 = 1.0 - EPS_T
    corners = (a, b, c)
    for k in range(3):
        p = corners[k]
        q = corners[(k + 1) % 3]
        m = np.cross(n, q - p)  # inward normal of edge pq within the plane (faces wound about n)
        num = m @ (x - p)
        den = m @ d
        tol = 1e-12 * (np.sqrt(m @ m) * scale)
        if abs(den) < 1e-300:
            if num <= tol:
                return False
        else:
            t = -num / den
            if den > 0:
                if t > t0:
                    t0 = t
            else:
                if t < t1:
                    t1 = t
        if t1 - t0 <= EPS_T:
            return False
    return True


@numba.njit(cache=True)
def segment_blocked(x, o, x_vertex, o_vertex, node_min, node_max, node_left, node_right, node_start,
                    node_count, tri, tri_vertex, scale):
    """(15) True when the open segment x -> o crosses a triangle incident to neither x_vertex nor o_vertex."""
    d = o - x
    pad = 1e-9 * scale
    stack = np.empty(128, dtype=np.int64)
    top = 0
    if len(node_min) == 0 or len(tri) == 0:
        return False
    stack[0] = 0
    top = 1
    while top > 0:
        top -= 1
        nd = stack[top]
        if not _seg_box(x[0], x[1], x[2], d[0], d[1], d[2], node_min[nd], node_max[nd], pad):
            continue
        if node_left[nd] < 0:
            s = node_start[nd]
            for k in range(s, s + node_count[nd]):
                tv = tri_vertex[k]
                if tv[0] == o_vertex or tv[1] == o_vertex or tv[2] == o_vertex:
                    continue
                if x_vertex >= 0 and (tv[0] == x_vertex or tv[1] == x_vertex or tv[2] == x_vertex):
                    continue
                if _seg_tri(x, d, tri[k, 0], tri[k, 1], tri[k, 2], scale):
                    return True
        else:
            stack[top] = node_left[nd]
            stack[top + 1] = node_right[nd]
            top += 2
    return False


@numba.njit(cache=True, parallel=True)
def _blocked_many(x, o, xv, ov, node_min, node_max, node_left, node_right, node_start, node_count, tri,
                  tri_vertex, scale, out):
    for i in numba.prange(len(x)):
        out[i] = segment_blocked(x[i], o[i], xv[i], ov[i], node_min, node_max, node_left, node_right,
                                 node_start, node_count, tri, tri_vertex, scale)


def blocked(bvh: Bvh, x: NDArray[np.float64], o: NDArray[np.float64], *, x_vertex: NDArray[np.int64] | None = None,
            o_vertex: NDArray[np.int64] | None = None) -> NDArray[np.bool_]:
    """(15) for S segments x (S, 3) -> o (S, 3): True where blocked (delta = 0).

    x_vertex / o_vertex: (S,) mesh vertex numbers of the ends (-1 for a point that is no vertex);
    triangles incident to them are ignored.
    """
    x = np.ascontiguousarray(np.asarray(x, dtype=np.float64).reshape(-1, 3))
    o = np.ascontiguousarray(np.asarray(o, dtype=np.float64).reshape(-1, 3))
    n = len(x)
    xv = np.full(n, -1, dtype=np.int64) if x_vertex is None else np.asarray(x_vertex, dtype=np.int64)
    ov = np.full(n, -1, dtype=np.int64) if o_vertex is None else np.asarray(o_vertex, dtype=np.int64)
    out = np.zeros(n, dtype=np.bool_)
    if n:
        _blocked_many(x, o, xv, ov, *bvh.arrays(), bvh.scale, out)
    return out

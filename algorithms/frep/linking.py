"""Linking surface points into quads (spec/frep.md §3, the paper's §3.2).

Every column's inside nodes form runs [b, t]; the non-empty voxels with one x form a vertical
section (axes y, z), those with one y a horizontal section (axes x, z). Each surface point (a
run's bottom or top) lies in one section of each kind.

**Neighbour tracing.** The paper traces a section's contour voxel by voxel "like a wheel":
from the current voxel and the last move it tests the neighbours right, front, left, back and
takes the first non-empty one; the next voxel holding a surface point is the next neighbour
along the contour. Between two surface points the wheel only climbs or descends straight runs
of voxels, so the same walk is computed here on the runs directly (a run-length form of the
same 4-connected contour, interior on the left, counter-clockwise in the section's (u, z)
plane), for all points of all sections at once:

* from the top of run R = [b, t] in column u (moving towards u - 1):
  - if column u - 1 has a run R' = [b', t'] holding row t: when t' = t the next point is
    top(R'); when t' > t the wheel climbs the side of R': if the next run R2 above R in
    column u starts at b2 <= t' the next point is bottom(R2), else top(R');
  - otherwise the wheel descends the side of R: the highest run of column u - 1 whose top is
    in [b, t - 1] gives top(that run); if none, the wheel turns round under R: bottom(R);
* from the bottom of R (moving towards u + 1): the same, turned by 180 degrees.

This gives ``succ`` in the vertical sections (u = j) and in the horizontal ones (u = i): two
permutations of the points (every contour is a cycle).

**Quads.** From A go down the vertical section to B = succ_v(A), right along B's horizontal
section to C (the contour neighbour of B in column i + 1: succ_h(B) or pred_h(B), depending on
whether the surface faces up, down or sideways there), up C's vertical section to D = pred_v(C),
left along D's horizontal section; if that returns to A, ABCD is a quad, stored as the triangles
ABC and ACD. Where the walk does not close, the mesh has a hole.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .objects import FRepObject
from .sampling import Samples

DIAGONALS = ("AC", "shorter")


def section_successors(s: Samples, *, axis: int) -> NDArray[np.int64]:
    """succ along the section contours: axis=0 vertical sections (fixed x, u = j),
    axis=1 horizontal sections (fixed y, u = i). Returns (P,) next point ids."""
    sec = s.run_i if axis == 0 else s.run_j
    u = s.run_j if axis == 0 else s.run_i
    b, t = s.run_b, s.run_t
    nrow = int(max(t.max(initial=0), 0)) + 3
    ncol = int(max(u.max(initial=0), 0)) + 3
    colkey = sec * ncol + (u + 1)  # u + 1 so that u - 1 >= 0
    key = colkey * nrow + b
    order = np.argsort(key, kind="stable")
    skey, scol = key[order], colkey[order]
    sb, st = b[order], t[order]
    top_pt, bot_pt = s.run_top[order], s.run_bottom[order]
    nr = len(order)
    pos = np.empty(nr, dtype=np.int64)
    pos[order] = np.arange(nr)  # sorted position of every run

    def last_at_or_below(col: NDArray, row: NDArray) -> tuple[NDArray, NDArray]:
        """Index (sorted) of the last run of column col with b' <= row, and whether it exists."""
        k = np.searchsorted(skey, col * nrow + row, side="right") - 1
        kc = np.clip(k, 0, max(nr - 1, 0))
        return kc, (k >= 0) & (scol[kc] == col)

    succ = np.full(len(s.points), -1, dtype=np.int64)
    R = np.arange(nr)  # sorted run indices
    # ---- from the top of R, towards u - 1
    left = scol - 1
    k, found = last_at_or_below(left, st)
    holds = found & (st[k] >= st)  # R' holds row t
    nxt = np.where(holds, top_pt[k], -1)
    climb = holds & (st[k] > st)
    r2 = np.clip(R + 1, 0, nr - 1)
    r2_ok = climb & (R + 1 < nr) & (scol[r2] == scol) & (sb[r2] <= st[k])
    nxt = np.where(r2_ok, bot_pt[r2], nxt)
    # descend: the highest run of column u - 1 with top in [b, t - 1]; the candidate k (last with
    # b' <= t) has t' < t when R' does not exist
    desc_ok = ~holds & found & (st[k] >= sb)
    nxt = np.where(~holds & desc_ok, top_pt[k], nxt)
    nxt = np.where(~holds & ~desc_ok, bot_pt, nxt)  # turn round under R
    succ[top_pt] = nxt
    # ---- from the bottom of R, towards u + 1 (the same, turned by 180 degrees)
    right = scol + 1
    k, found = last_at_or_below(right, sb)
    holds = found & (st[k] >= sb)  # R' holds row b
    nxt = np.where(holds, bot_pt[k], -1)
    descend = holds & (sb[k] < sb)
    r2 = np.clip(R - 1, 0, nr - 1)
    r2_ok = descend & (R - 1 >= 0) & (scol[r2] == scol) & (st[r2] >= sb[k])
    nxt = np.where(r2_ok, top_pt[r2], nxt)
    # climb the side of R: the lowest run of column u + 1 with bottom in [b + 1, t]
    k2 = np.where(found, k + 1, np.searchsorted(skey, right * nrow + sb, side="right"))
    k2c = np.clip(k2, 0, max(nr - 1, 0))
    up_ok = (k2 < nr) & (scol[k2c] == right) & (sb[k2c] <= st)
    nxt = np.where(~holds & up_ok, bot_pt[k2c], nxt)
    nxt = np.where(~holds & ~up_ok, top_pt, nxt)  # turn round over R
    succ[bot_pt] = nxt
    return succ


@dataclass(frozen=True, eq=False)
class Linked:
    """Quads (Q, 4) of point ids after the walk, their triangles (2Q, 3), oriented outward."""

    succ_v: NDArray[np.int64]
    succ_h: NDArray[np.int64]
    quads: NDArray[np.int64]
    faces: NDArray[np.int64]
    dropped: int  # quads removed because they would make an edge non-manifold


def inverse(perm: NDArray[np.int64]) -> NDArray[np.int64]:
    inv = np.full(len(perm), -1, dtype=np.int64)
    inv[perm] = np.arange(len(perm))
    return inv


def link(s: Samples, obj: FRepObject, *, diagonal: str = "AC") -> Linked:
    if diagonal not in DIAGONALS:
        raise ValueError(f"diagonal must be one of {DIAGONALS}, got {diagonal!r}")
    sv = section_successors(s, axis=0)
    sh = section_successors(s, axis=1)
    pv, ph = inverse(sv), inverse(sh)
    ci = s.point_col[:, 0]
    run = s.point_run
    A = np.arange(len(s.points))
    B = sv[A]  # down the vertical section
    quads = []
    for C in (sh[B], ph[B]):  # right along B's horizontal section: the neighbour in column i + 1
        D = pv[C]  # up C's vertical section
        closed = (ci[C] == ci[B] + 1) & ((sh[D] == A) | (ph[D] == A))  # left along D's section: A?
        quads.append(np.stack([A, B, C, D], axis=1)[closed])
        # where the horizontal contour turns round at the x-extreme of its section, "right" is
        # the other end of B's run and "left" the other end of A's run: a side quad (zero area
        # seen along z); the vertical contour runs the other way on the far side of the run
        for D in (pv[C], sv[C]):
            closed = (run[C] == run[B]) & (run[D] == run[A]) & ((sh[D] == A) | (ph[D] == A))
            quads.append(np.stack([A, B, C, D], axis=1)[closed])
    q = np.concatenate(quads)
    distinct = (q[:, 0] != q[:, 1]) & (q[:, 0] != q[:, 2]) & (q[:, 0] != q[:, 3]) & \
               (q[:, 1] != q[:, 2]) & (q[:, 1] != q[:, 3]) & (q[:, 2] != q[:, 3])
    q = q[distinct]
    if len(q):
        sq = np.sort(q, axis=1)
        n = len(s.points)
        k1, k2 = sq[:, 0] * n + sq[:, 1], sq[:, 2] * n + sq[:, 3]  # two int64 keys (n^4 could overflow)
        o = np.lexsort((k2, k1))
        first = np.r_[True, (k1[o][1:] != k1[o][:-1]) | (k2[o][1:] != k2[o][:-1])]
        q = q[np.sort(o[first])]
    # orientation: the walk turns one way where the surface faces +z and the other where it
    # faces -z, so each quad is oriented by the outward normal -grad F at its centre
    P = s.points
    qn = np.cross(P[q[:, 2]] - P[q[:, 0]], P[q[:, 3]] - P[q[:, 1]])
    g = obj.gradient(P[q].mean(axis=1))
    flip = np.einsum("ij,ij->i", qn, -g) < 0
    q = np.where(flip[:, None], q[:, ::-1], q)
    if diagonal == "shorter":
        ac = np.linalg.norm(P[q[:, 0]] - P[q[:, 2]], axis=1)
        bd = np.linalg.norm(P[q[:, 1]] - P[q[:, 3]], axis=1)
        q = np.where((bd < ac)[:, None], np.roll(q, -1, axis=1), q)
    faces = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]).reshape(2, -1, 3).transpose(1, 0, 2).reshape(-1, 3)
    faces, dropped = _manifold_quads(faces)
    keep_q = np.ones(len(q), bool)
    return Linked(sv, sh, q[keep_q], faces, dropped)


def _manifold_quads(faces: NDArray[np.int64]) -> tuple[NDArray[np.int64], int]:
    """Drop the quads (face pairs 2k, 2k+1) that have an edge used by more than two faces or a
    half-edge used twice (overlapping walks at silhouettes); they become holes to fill."""
    from ..topology import edge_table, halfedges

    dropped = 0
    for _ in range(10):  # a few passes: removing quads can only lower the counts
        if not len(faces):
            break
        et = edge_table(faces)
        he = halfedges(faces)
        _, inv, hcount = np.unique(he[:, 0] * (int(faces.max()) + 1) + he[:, 1], return_inverse=True,
                                   return_counts=True)
        bad_he = (et.counts[et.halfedge_edge] > 2) | (hcount[inv.ravel()] > 1)
        bad_face = bad_he.reshape(-1, 3).any(axis=1)
        if not bad_face.any():
            break
        bad_quad = bad_face.reshape(-1, 2).any(axis=1)
        dropped += int(bad_quad.sum())
        faces = faces.reshape(-1, 2, 3)[~bad_quad].reshape(-1, 3)
    return faces, dropped

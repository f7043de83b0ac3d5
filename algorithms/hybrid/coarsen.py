"""A finishing pass after Stage III (choice, not in the paper): coarsening by half-edge collapses.

Ruppert refinement splits a triangle as soon as one criterion fails, so its triangles end between
about half and all of the allowed size: with the chordal criterion (max_deviation) the median
triangle of a refined cone uses only half the tolerance. This pass removes the vertices the criteria
do not need: an interior vertex v is moved onto a neighbour w (its two triangles on edge (v, w)
die, the rest of its fan take w) when every new triangle

- is counter-clockwise in (u, v) (the parameter triangulation stays valid: v's star is star-shaped
  from w),
- keeps the minimum 3D angle bound (min_angle; where the fan was below it already, at an excepted
  trim corner, it may not get worse),
- and meets the size criteria of the refinement that are on: longest 3D edge <= max_edge, every
  new edge's chord / arc >= chord_arc, chordal error <= max_deviation (chordal.py).

So every bound the refinement guaranteed still holds, with fewer triangles. Border vertices never
go (they are on F = 0 or on the sides of P, and seams stay welded); a vertex can go onto a border
vertex. Among the admissible targets of v the one leaving the largest smallest angle is taken;
vertices with the most slack (the smallest chordal error or longest-edge ratio after the collapse)
go first, and in one pass no two collapses touch the same triangle (v's neighbours wait for the next
pass). All candidates of a pass are assessed together (numpy, one surface call for the chordal
errors, one for the chord / arc ratios).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .cdt import Triangulation
from .chordal import chord_arc_ratios, chordal_errors, gauss_newton_step
from .smooth import _longest, _min_angles

TRY_PER_VERTEX = 2  # admissible collapses (by angle) per vertex whose size criteria are assessed
SLACK = 0.9  # a vertex is a candidate when its triangles use at most this share of a size bound


def _candidates(faces: NDArray[np.int64], movable: NDArray[np.bool_]
                ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.bool_], NDArray[np.int64],
                           NDArray[np.int64]]:
    """The collapses to assess: (cand_v, cand_w, mid, new_tri (M, 3), owner (M,)). Each (v, w) with v
    movable and w a neighbour: v goes onto w (mid False); and once per edge of two movable vertices,
    both go onto one new vertex that takes w's index (mid True: placed at the edge's middle by the
    caller). new_tri: the triangles each collapse leaves around the (moved) w, owner: its candidate."""
    nf = len(faces)
    inc_t = np.repeat(np.arange(nf), 3)
    inc_v = faces.ravel()
    order = np.argsort(inc_v, kind="stable")
    inc_t, inc_v = inc_t[order], inc_v[order]
    pv = np.repeat(inc_v, 3)
    pw = faces[inc_t].ravel()
    keep = (pw != pv) & movable[pv]
    n = int(faces.max()) + 1
    key = np.unique(pv[keep] * n + pw[keep])  # the (v, w) pairs, sorted by (v, w)
    hv, hw = key // n, key % n
    # the triangles around v without w, v renamed w
    start = np.searchsorted(inc_v, hv, side="left")
    count = np.searchsorted(inc_v, hv, side="right") - start
    owner = np.repeat(np.arange(len(hv)), count)
    idx = np.arange(owner.size) - np.repeat(np.cumsum(count) - count, count) + np.repeat(start, count)
    F = faces[inc_t[idx]]
    keep = ~(F == hw[owner][:, None]).any(axis=1)
    F, owner = F[keep], owner[keep]
    F = np.where(F == hv[owner][:, None], hw[owner][:, None], F)
    # midpoint collapses: edge (v, w), v < w, both movable: the half-edge rows of (v, w) and of (w, v)
    # (the latter with v renamed back to w)
    both = np.flatnonzero(movable[hw] & (hv < hw))
    partner = np.searchsorted(key, hw[both] * n + hv[both])
    mid_id = np.full(len(hv), -1)
    mid_id[both] = len(hv) + np.arange(len(both))
    part_id = np.full(len(hv), -1)
    part_id[partner] = len(hv) + np.arange(len(both))
    r1 = np.flatnonzero(mid_id[owner] >= 0)
    r2 = np.flatnonzero(part_id[owner] >= 0)
    o2 = owner[r2]
    F2 = np.where(F[r2] == hw[o2][:, None], hv[o2][:, None], F[r2])  # rows of (w, v): v back to w
    cand_v = np.r_[hv, hv[both]]
    cand_w = np.r_[hw, hw[both]]
    mid = np.r_[np.zeros(len(hv), dtype=bool), np.ones(len(both), dtype=bool)]
    new_tri = np.concatenate([F, F[r1], F2])
    new_owner = np.r_[owner, mid_id[owner[r1]], part_id[o2]]
    return cand_v, cand_w, mid, new_tri, new_owner


def coarsen_pass(tri: Triangulation, *, min_angle: float, max_deviation: float | None = None,
                 max_edge: float | None = None, chord_arc: float = 0.0,
                 only: NDArray[np.bool_] | None = None, median_floor: float | None = None
                 ) -> tuple[int, NDArray[np.bool_]]:
    """One pass; returns the number of collapses and the vertices whose triangles changed (a mask).
    only: (optional mask) the vertices that may go: a vertex whose triangles are unchanged since a
    pass found no admissible collapse for it has none still. median_floor: (degrees) collapses are
    taken only while at most half the triangles have a smallest angle below this (or, where more
    have already, while that share does not grow), so the median minimum angle stays above it."""
    faces = tri.faces()
    if not len(faces):
        return 0, np.zeros(len(tri.uv), dtype=bool)
    n = len(tri.uv)
    uv = np.array(tri.uv, dtype=np.float64)
    p3 = np.array(tri.p3, dtype=np.float64)
    movable = tri.interior_mask(faces, only)
    # only vertices whose triangles have slack: a collapse grows them (about 1.5 times in area)
    if max_deviation is not None:
        fan_err = np.zeros(n)
        np.maximum.at(fan_err, faces.ravel(), np.repeat(chordal_errors(tri.surface, p3[faces], uv[faces]), 3))
        movable &= fan_err <= SLACK * max_deviation
    if max_edge is not None:
        fan_len = np.zeros(n)
        np.maximum.at(fan_len, faces.ravel(), np.repeat(_longest(p3[faces]), 3))
        movable &= fan_len <= SLACK * max_edge
    if not movable.any():
        return 0, np.zeros(len(tri.uv), dtype=bool)
    cv, cw, mid, F, owner = _candidates(faces, movable)
    if not len(cv):
        return 0, np.zeros(len(tri.uv), dtype=bool)
    nc = len(cv)
    # where each candidate puts w: its own place, or the middle of the edge (on the surface)
    tuv = uv[cw].copy()
    tp3 = p3[cw].copy()
    at_w = F == cw[owner][:, None]
    if mid.any():
        # the merged vertex at the 3D mean of its new neighbours, found on the surface by Gauss-Newton
        # from the edge's middle (smooth.py's move, done at once)
        rows_m = np.flatnonzero(mid[owner])
        om = owner[rows_m]
        nbr = np.where(at_w[rows_m], 0.0, 1.0)  # each neighbour is in two of the fan's triangles
        goal = np.zeros((nc, 3))
        np.add.at(goal, om, np.einsum("ki,kij->kj", nbr, p3[F[rows_m]]))
        cnt = np.bincount(om, nbr.sum(1), minlength=nc)
        ids_m = np.flatnonzero(mid)
        goal = goal[ids_m] / cnt[ids_m, None]
        x = 0.5 * (uv[cv[ids_m]] + uv[cw[ids_m]])
        a, b, c, d = tri.domain
        hu, hv = 1e-7 * (b - a), 1e-7 * (d - c)
        R = tri.surface(x[:, 0], x[:, 1])
        for _ in range(2):
            q = tri.surface(np.r_[x[:, 0] + hu, x[:, 0]], np.r_[x[:, 1], x[:, 1] + hv])
            ru, rv = (q[:len(x)] - R) / hu, (q[len(x):] - R) / hv
            x = x + np.stack(gauss_newton_step(ru, rv, goal - R), axis=1)
            x[:, 0] = np.clip(x[:, 0], a, b)
            x[:, 1] = np.clip(x[:, 1], c, d)
            R = tri.surface(x[:, 0], x[:, 1])
        tuv[ids_m], tp3[ids_m] = x, R
    T2, T3 = uv[F], p3[F]
    rows, cols = np.nonzero(at_w)
    T2[rows, cols] = tuv[owner[rows]]
    T3[rows, cols] = tp3[owner[rows]]
    area = ((T2[:, 1, 0] - T2[:, 0, 0]) * (T2[:, 2, 1] - T2[:, 0, 1])
            - (T2[:, 1, 1] - T2[:, 0, 1]) * (T2[:, 2, 0] - T2[:, 0, 0]))
    scale = np.abs(T2[:, 1] - T2[:, 0]).sum(1) + np.abs(T2[:, 2] - T2[:, 0]).sum(1)
    ok_tri = area > 1e-12 * scale * scale
    ang = np.where(ok_tri, _min_angles(T3), -1.0)
    # the bound on the smallest angle: min_angle, or the fans' own smallest where they are below already
    face_min = _min_angles(p3[faces])
    fan_min = np.full(n, np.inf)
    np.minimum.at(fan_min, faces.ravel(), np.repeat(face_min, 3))
    new_min = np.full(nc, np.inf)
    np.minimum.at(new_min, owner, ang)
    ok = new_min >= np.minimum(min_angle, np.where(mid, np.minimum(fan_min[cv], fan_min[cw]), fan_min[cv]))
    # the size criteria (surface calls) only for each vertex's TRY_PER_VERTEX best-shaped collapses
    order = np.lexsort((-new_min, cv))
    first = np.r_[0, np.flatnonzero(np.diff(cv[order])) + 1]
    okr = ok[order]
    # rank among the admissible ones: the admissible predecessors within the vertex's group
    cum = np.cumsum(okr) - okr
    grp_start = np.repeat(cum[first], np.diff(np.r_[first, nc]))
    adm_rank = np.empty(nc, dtype=np.int64)
    adm_rank[order] = cum - grp_start
    ok &= adm_rank < TRY_PER_VERTEX
    slack = np.zeros(nc)
    if max_edge is not None:
        worst = np.zeros(nc)
        np.maximum.at(worst, owner, _longest(T3))
        ok &= worst <= max_edge
        slack = np.maximum(slack, worst / max_edge)
    if chord_arc > 0 and ok.any():
        # the edges at the moved w in the candidates' triangles (the others are unchanged)
        r = np.flatnonzero(ok[owner[rows]])
        rr, cc = rows[r], cols[r]
        o = owner[rr]
        ends_uv, ends_p3 = [], []
        for k in (1, 2):
            other = F[rr, (cc + k) % 3]
            ends_uv.append(np.stack([tuv[o], uv[other]], 1))
            ends_p3.append(np.stack([tp3[o], p3[other]], 1))
        ratio = chord_arc_ratios(tri.surface, np.concatenate(ends_uv), np.concatenate(ends_p3))
        low = np.full(nc, np.inf)
        np.minimum.at(low, np.r_[o, o], ratio)
        ok &= low >= chord_arc
    if max_deviation is not None and ok.any():
        sel = ok[owner]
        err = chordal_errors(tri.surface, T3[sel], T2[sel])
        worst = np.zeros(nc)
        np.maximum.at(worst, owner[sel], err)
        ok &= worst <= max_deviation
        slack = np.maximum(slack, worst / max_deviation)
    good = np.flatnonzero(ok)
    if not len(good):
        return 0, np.zeros(len(tri.uv), dtype=bool)
    # the most slack first; among a vertex's admissible collapses, the largest smallest angle first
    best = good[np.lexsort((-new_min[good], slack[good]))]
    # the median budget: how many triangles under median_floor each collapse adds (new minus old)
    delta = np.zeros(nc, dtype=np.int64)
    if median_floor is not None:
        low = face_min < median_floor
        low_fan = np.bincount(faces.ravel(), np.repeat(low, 3), minlength=n).astype(np.int64)
        e = np.sort(np.stack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], 1), axis=2).reshape(-1, 2)
        ekey, inv = np.unique(e[:, 0] * n + e[:, 1], return_inverse=True)
        low_edge = np.bincount(inv, np.repeat(low, 3), minlength=len(ekey)).astype(np.int64)
        ck = np.minimum(cv, cw) * n + np.maximum(cv, cw)
        shared = low_edge[np.clip(np.searchsorted(ekey, ck), 0, len(ekey) - 1)]
        old_low = np.where(mid, low_fan[cv] + low_fan[cw] - shared, low_fan[cv])
        delta = np.bincount(owner, ang < median_floor, minlength=nc).astype(np.int64) - old_low
        n_low, n_tri = int(low.sum()), len(faces)
    tv = tri.tv

    def star(x: int) -> list[int]:  # x and its neighbours: the vertices of its fan
        return [y for t in tri.fan(x) for y in tv[t]]

    locked = np.zeros(n, dtype=bool)
    done = 0
    for c in best.tolist():
        v, w = int(cv[c]), int(cw[c])
        if locked[v] or (mid[c] and locked[w]):
            continue
        if median_floor is not None:
            if 2 * (n_low + delta[c]) > max(n_tri - 2, 2 * n_low * (n_tri - 2) / n_tri):
                continue
            n_low += int(delta[c])
            n_tri -= 2
        # every vertex whose triangles change: v's star, and w's too when w moves
        locked[star(v) + (star(w) if mid[c] else [])] = True
        tri.collapse(v, w)
        if mid[c]:
            tri.uv[w] = (float(tuv[c, 0]), float(tuv[c, 1]))
            tri.p3[w] = (float(tp3[c, 0]), float(tp3[c, 1]), float(tp3[c, 2]))
        done += 1
    return done, locked

"""The boundary indicator field BIAF (spec/repair.md §4, eqs. 11-16).

An elementary source {O, n_O, tau_O, h_O} acts on {X, n_X} with the force f = delta d h_O Q (11,
15). Q is linear in n_X, so f = H n_X with the tensor (12)-(14)

    H_O = delta_XO h_O g d s_O^T,   g = q12 (1 + k_i q4) (13),   s_O = tau_O x d,

(the factor (I - d d^T) of (14) drops out because s_O is perpendicular to d), and many sources
superpose: H(X) = sum_O H_O(X).

Speed: the sum over sources is one fused numba loop per evaluation point (parallel over points),
so no (N, M) temporaries are made and memory stays O(N + M) whatever the chunk; q4 uses
s_O . n_O = (tau_O x d) . n_O = -d . b_O, so a pair costs one sqrt, one exp and ~40 flops.
Pairs whose weight is negligible (q1 < 1e-7 even after free points shorten them as much as they
can) are skipped before the shielding test, which is what keeps full mode affordable.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from ..boundary import LoopFrame
from ..params import FieldParams
from .free_points import FreePoints, lattice_args, q2_lattice_capped
from .quality import g0
from .shielding import Bvh, segment_blocked_hint

Arr = NDArray[np.float64]
PRUNE_GAUSS = 4.0  # exp(-16) ~ 1e-7: relative weight below which a Gaussian source is skipped


def prune_bound2(lc: Any, kernel: int) -> NDArray[np.float64]:
    """The kernels' squared pruning distance for L_c (a scalar or one per point): (PRUNE_GAUSS L_c)^2
    for the Gaussian kernel (0), 1e300 (never prune) for the heavy-tailed one."""
    lc = np.asarray(lc, dtype=np.float64)
    return np.minimum((PRUNE_GAUSS * lc) ** 2, 1e300) if kernel == 0 else np.full(lc.shape, 1e300)
NO_GROUP = -2  # a point that excludes no group of sources
SERIAL_BELOW = 16  # fewer points than this: one thread (a tracing step)
CHORD_SLACK = 1.25  # coherence across points only for a point near the chord of its key points
KEY_MEMORY = 32_000_000  # bytes of key-point verdicts per chunk in full mode (the chunk shrinks to fit)


@dataclass(frozen=True, eq=False)
class Sources:
    """M elementary sources (boundary points). group: what a point excludes when it belongs to it
    (the island, or the loop); loop/pos/loop_len: the loop and position along it (for excluding a
    neighbourhood of a point along its own loop); vertex: mesh vertex numbers (-1 if none)."""

    points: Arr
    tangent: Arr
    normal: Arr
    outward: Arr
    charge: Arr
    vertex: NDArray[np.int64]
    island: NDArray[np.int64]
    group: NDArray[np.int64]
    loop: NDArray[np.int64]
    pos: NDArray[np.int64]
    loop_len: NDArray[np.int64]

    def __len__(self) -> int:
        return int(len(self.points))

    def subset(self, keep: NDArray[np.bool_]) -> Sources:
        idx = np.flatnonzero(keep)  # once, not once per field
        return Sources(*(getattr(self, f).take(idx, axis=0) for f in self.__dataclass_fields__))


def sources_from_frames(frames: Sequence[LoopFrame], *, loop_ids: Sequence[int] | None = None,
                        group: str = "island") -> Sources:
    """Sources from loop frames (spec §2 data). group: "island" or "loop" (the unit a point excludes)."""
    ids = list(range(len(frames))) if loop_ids is None else list(loop_ids)
    if not frames:
        z3, zi = np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
        return Sources(z3, z3, z3, z3, np.zeros(0), zi, zi, zi, zi, zi, zi)
    cat = np.concatenate
    isl = cat([np.full(len(f.vertices), f.island) for f in frames]).astype(np.int64)
    loop = cat([np.full(len(f.vertices), k) for k, f in zip(ids, frames)]).astype(np.int64)
    return Sources(
        np.ascontiguousarray(cat([f.points for f in frames])), np.ascontiguousarray(cat([f.tangent for f in frames])),
        np.ascontiguousarray(cat([f.normal for f in frames])), np.ascontiguousarray(cat([f.outward for f in frames])),
        cat([f.charge for f in frames]).astype(np.float64), cat([f.vertices for f in frames]).astype(np.int64),
        isl, isl.copy() if group == "island" else loop.copy(), loop,
        cat([np.arange(len(f.vertices)) for f in frames]).astype(np.int64),
        cat([np.full(len(f.vertices), len(f.vertices)) for f in frames]).astype(np.int64))


@numba.njit(cache=True, fastmath=True)
def _q1(l2, lc2, kernel):
    if kernel == 0:
        return np.exp(-l2 / lc2)
    return 1.0 / (1.0 + l2 / lc2)


@numba.njit(cache=True, inline="always")
def _excluded(j, g, lo, ps, w, sgrp, sloop, spos, slen):
    """Is source j excluded for a point of group g, loop lo, position ps and window w: the same
    group (its own island), or on the point's own loop within its window of positions (hole
    splitting, tunnels)? The point's values come as scalars and the test is one expression: the
    pair loops then compile to straight code (indexing the point's arrays per pair, with early
    returns, made them ~20x slower)."""
    dp = abs(spos[j] - ps)
    return sgrp[j] == g or (w >= 0 and sloop[j] == lo and min(dp, slen[j] - dp) <= w)


@numba.njit(cache=True, fastmath=True)
def _nearest_admissible(i, x, xgrp, xloop, xpos, xwin, o, sgrp, sloop, spos, slen, plain):
    """(squared distance, index) of the nearest source point i may use (index -1 if none):
    pass 1 of both kernels, no exp, cheap."""
    x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
    g, lo, ps, xw = xgrp[i], xloop[i], xpos[i], xwin[i]
    best = 1e300
    bj = -1
    for j in range(o.shape[0]):
        if not plain and _excluded(j, g, lo, ps, xw, sgrp, sloop, spos, slen):
            continue
        r0 = o[j, 0] - x0
        r1 = o[j, 1] - x1
        r2 = o[j, 2] - x2
        l2 = r0 * r0 + r1 * r1 + r2 * r2
        if l2 < best:
            best = l2
            bj = j
    return best, bj


@numba.njit(cache=True, fastmath=True)
def _light_point(i, x, xgrp, xloop, xpos, xwin, o, tau, b, h, sgrp, sloop, spos, slen, lc2, ki, kernel, prune2,
                 out_h, out_near, out_dist):
    """Light mode (M1) at point i: H, no shielding, q12 = q1(L). Also the nearest source."""
    m = o.shape[0]
    x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
    h00 = h01 = h02 = h10 = h11 = h12 = h20 = h21 = h22 = 0.0
    plain = xgrp[i] == NO_GROUP and xwin[i] < 0
    best, bj = _nearest_admissible(i, x, xgrp, xloop, xpos, xwin, o, sgrp, sloop, spos, slen, plain)
    lim = best + prune2  # relative pruning: weight below exp(-16) of the nearest source's
    g, lo, ps, xw = xgrp[i], xloop[i], xpos[i], xwin[i]
    for j in range(m):  # pass 2: the field
        if not plain and _excluded(j, g, lo, ps, xw, sgrp, sloop, spos, slen):
            continue
        r0 = o[j, 0] - x0
        r1 = o[j, 1] - x1
        r2 = o[j, 2] - x2
        l2 = r0 * r0 + r1 * r1 + r2 * r2
        if l2 > lim or l2 < 1e-300:
            continue
        il = 1.0 / np.sqrt(l2)
        d0, d1, d2 = r0 * il, r1 * il, r2 * il  # (6)
        t0, t1, t2 = tau[j, 0], tau[j, 1], tau[j, 2]
        s0 = t1 * d2 - t2 * d1  # s_O = tau_O x d
        s1 = t2 * d0 - t0 * d2
        s2 = t0 * d1 - t1 * d0
        q4 = 0.5 * (1.0 - (d0 * b[j, 0] + d1 * b[j, 1] + d2 * b[j, 2]))  # (7): s_O . n_O = -d . b_O
        w = h[j] * _q1(l2, lc2, kernel) * (1.0 + ki * q4)  # h_O g, (13) with q12 = q1(L)
        wd0, wd1, wd2 = w * d0, w * d1, w * d2
        h00 += wd0 * s0
        h01 += wd0 * s1
        h02 += wd0 * s2
        h10 += wd1 * s0
        h11 += wd1 * s1
        h12 += wd1 * s2
        h20 += wd2 * s0
        h21 += wd2 * s1
        h22 += wd2 * s2
    out_h[i, 0], out_h[i, 1], out_h[i, 2] = h00, h01, h02
    out_h[i, 3], out_h[i, 4], out_h[i, 5] = h10, h11, h12
    out_h[i, 6], out_h[i, 7], out_h[i, 8] = h20, h21, h22
    out_near[i] = bj
    out_dist[i] = np.sqrt(best) if bj >= 0 else np.inf


@numba.njit(cache=True, parallel=True)
def _field_light(x, xgrp, xloop, xpos, xwin, o, tau, b, h, sgrp, sloop, spos, slen, lc2, ki, kernel, prune2,
                 out_h, out_near, out_dist):
    """Light mode over all points, parallel (threads over points); lc2, prune2: (N,) per point."""
    for i in numba.prange(x.shape[0]):
        _light_point(i, x, xgrp, xloop, xpos, xwin, o, tau, b, h, sgrp, sloop, spos, slen, lc2[i], ki, kernel,
                     prune2[i], out_h, out_near, out_dist)


@numba.njit(cache=True)
def _field_light_serial(x, xgrp, xloop, xpos, xwin, o, tau, b, h, sgrp, sloop, spos, slen, lc2, ki, kernel, prune2,
                        out_h, out_near, out_dist):
    """Light mode, one thread: for the few points of a tracing step (no thread start-up cost)."""
    for i in range(x.shape[0]):
        _light_point(i, x, xgrp, xloop, xpos, xwin, o, tau, b, h, sgrp, sloop, spos, slen, lc2[i], ki, kernel,
                     prune2[i], out_h, out_near, out_dist)


@numba.njit(cache=True)
def _q2_ratio(xi, oj, gr, cap):
    """(4) q2 / L of the segment X -> O (cap: q2_lattice_capped's; 1e300 = exact)."""
    r0 = oj[0] - xi[0]
    r1 = oj[1] - xi[1]
    r2 = oj[2] - xi[2]
    length = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    return q2_lattice_capped(xi, oj, length, gr[0], gr[1], gr[2], gr[3], cap) / length


# reassociation etc. for the sums, but no "no-inf / no-nan" assumptions (inf marks "no source")
FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}


@numba.njit(cache=True)
def _narrow(x, oa, ob, cos2):
    """Do oa and ob subtend at most the coherence angle at x (cos2 = its squared cosine)?"""
    a0, a1, a2 = oa[0] - x[0], oa[1] - x[1], oa[2] - x[2]
    b0, b1, b2 = ob[0] - x[0], ob[1] - x[1], ob[2] - x[2]
    dot = a0 * b0 + a1 * b1 + a2 * b2
    na = a0 * a0 + a1 * a1 + a2 * a2
    nb = b0 * b0 + b1 * b1 + b2 * b2
    return dot > 0 and dot * dot >= cos2 * na * nb


@numba.njit(cache=True)
def _run_end(cand, sel, k, ns, sloop):
    """End (exclusive) of the run of consecutive sources of one loop starting at sel[k]."""
    e = k + 1
    while e < ns and cand[sel[e]] == cand[sel[e - 1]] + 1 and sloop[cand[sel[e]]] == sloop[cand[sel[k]]]:
        e += 1
    return e


@numba.njit(cache=True)
def _next_anchor(xi, o, cand, sel, a, e, stride, cos2):
    """The next anchor after sel[a] in a run ending at e: the farthest source at most ``stride``
    positions on whose direction from X is within the coherence angle of sel[a]'s (at least the
    next source, so a near source, whose neighbours subtend more than that angle, is exact)."""
    hi = min(a + stride, e - 1)
    bnd = a + 1
    oa = o[cand[sel[a]]]
    while bnd < hi and _narrow(xi, oa, o[cand[sel[bnd + 1]]], cos2):
        bnd += 1
    return bnd


@numba.njit(cache=True)
def _q2_pass(xi, cand, sel, ns, o, sloop, kept, ratio, stride, cos2, gr, lim):
    """(4) q2 / L for the candidates sel[:ns], and kept[c] = False where q2^2 > lim (the pair's
    weight is still below exp(-16) of the nearest source's after the free points shorten it:
    pruned like the candidate pass). With visibility coherence (FieldParams.shield_stride,
    coherence_deg): q2 / L is computed at anchors (_next_anchor) and interpolated linearly in
    between, and the pruning rule is then applied to the interpolated q2 (an error there only
    concerns weights near exp(-16)). The anchors' q2 sum stops once it is certainly beyond the
    limit; where both anchors are, the sources in between are pruned; where only one is, its q2
    is completed."""
    cap = np.sqrt(lim)
    k = 0
    while k < ns:
        e = _run_end(cand, sel, k, ns, sloop)
        a = k
        oa = o[cand[sel[a]]]
        ra = _q2_ratio(xi, oa, gr, cap)
        exact_a = ra * np.sqrt(_d2(xi, oa)) <= cap  # else the capped sum stopped early: a lower bound
        kept[sel[a]] = exact_a
        ratio[sel[a]] = ra
        while a < e - 1:
            bnd = _next_anchor(xi, o, cand, sel, a, e, stride, cos2)
            ob = o[cand[sel[bnd]]]
            rb = _q2_ratio(xi, ob, gr, cap)
            exact_b = rb * np.sqrt(_d2(xi, ob)) <= cap
            kept[sel[bnd]] = exact_b
            if bnd > a + 1:
                if not exact_a and not exact_b:
                    for t in range(a + 1, bnd):
                        kept[sel[t]] = False
                else:
                    if not exact_a:
                        ra = _q2_ratio(xi, o[cand[sel[a]]], gr, 1e300)
                    if not exact_b:
                        rb = _q2_ratio(xi, ob, gr, 1e300)
                    exact_b = True
                    for t in range(a + 1, bnd):
                        r = ra + (rb - ra) * (t - a) / (bnd - a)
                        ratio[sel[t]] = r
                        q2 = r * np.sqrt(_d2(xi, o[cand[sel[t]]]))
                        kept[sel[t]] = q2 * q2 <= lim
            ratio[sel[bnd]] = rb
            a = bnd
            ra = rb
            exact_a = exact_b
        k = e


@numba.njit(cache=True, inline="always")
def _d2(x, y):
    r0, r1, r2 = y[0] - x[0], y[1] - x[1], y[2] - x[2]
    return r0 * r0 + r1 * r1 + r2 * r2


@numba.njit(cache=True)
def _shield_pass(xi, xvi, cand, sel, ns, o, ov, sloop, vis, stride, cos2, bv, stack, work, istack):
    """(15) vis[sel[:ns]] = delta_XO, with visibility coherence (FieldParams.shield_stride,
    coherence_deg): anchors along each run of consecutive sources (_next_anchor) are tested
    exactly; between two tested sources that agree, the sources in between take their verdict;
    where they disagree the middle source is tested and both halves are treated the same way
    (bisection: a change of visibility costs O(log stride) segment tests). stride = 1 is exact.
    The last occluder found from X is tried first for the next segment."""
    occ = -1
    k = 0
    while k < ns:
        e = _run_end(cand, sel, k, ns, sloop)
        a = k
        ca = sel[a]
        hit, occ = segment_blocked_hint(xi, o[cand[ca]], xvi, ov[cand[ca]], bv[0], bv[1], bv[2], bv[3], bv[4],
                                        bv[5], bv[6], bv[7], occ, stack, work)
        vis[ca] = not hit
        while a < e - 1:
            bnd = _next_anchor(xi, o, cand, sel, a, e, stride, cos2)
            cb = sel[bnd]
            hit, occ = segment_blocked_hint(xi, o[cand[cb]], xvi, ov[cand[cb]], bv[0], bv[1], bv[2], bv[3], bv[4],
                                            bv[5], bv[6], bv[7], occ, stack, work)
            vis[cb] = not hit
            istack[0] = a
            istack[1] = bnd
            top = 1
            while top > 0:  # bisection of [lo, up] between tested ends
                top -= 1
                lo = istack[2 * top]
                up = istack[2 * top + 1]
                if up - lo <= 1:
                    continue
                cl, cu = sel[lo], sel[up]
                if vis[cl] == vis[cu]:
                    for t in range(lo + 1, up):
                        vis[sel[t]] = vis[cl]
                    continue
                mid = (lo + up) // 2
                cm = sel[mid]
                hit, occ = segment_blocked_hint(xi, o[cand[cm]], xvi, ov[cand[cm]], bv[0], bv[1], bv[2], bv[3],
                                                bv[4], bv[5], bv[6], bv[7], occ, stack, work)
                vis[cm] = not hit
                istack[2 * top] = lo
                istack[2 * top + 1] = mid
                istack[2 * top + 2] = mid
                istack[2 * top + 3] = up
                top += 2
            a = bnd
        k = e


@numba.njit(cache=True, inline="always")
def _verdict_class(v):
    """A key point's verdict as a class: 0 negligible (-1 or 0), 1 visible, 2 shielded, -1 none."""
    if v == -2:
        return -1
    return max(v, 0)


@numba.njit(cache=True, fastmath=FAST)
def _full_point(i, x, xv, xgrp, xloop, xpos, xwin, o, ov, tau, b, h, sgrp, sloop, spos, slen,
                lc2, ki, kernel, prune2, shrink2, stride, cos2,
                shield, node_box, node_child, node_start, node_count, tri, tri_vertex, tri_normal,
                scale,
                use_fp, g_origin, g_cell, g_dims, g_lattice,
                krow, n0, n1, p0, p1, wgt, kv, kr,
                out_h, out_near, out_dist, out_pairs):
    """Full mode (M2) at point i: shielding delta (15) and q12 = q1(q2) with free points (4, 8).

    The pairs kept by the Gaussian pruning are decided in two passes with visibility coherence:
    first q2 (_q2_pass, free points), which drops the pairs still negligible after the free points
    shorten them, then shielding (_shield_pass) of the rest. stride = 1 is exact everywhere.

    Coherence across points (FieldParams.point_stride): a key point (krow[i] >= 0) records its
    verdict per source in kv[krow[i]] (-2 excluded, -1 negligible by the candidate bound, 0 pruned
    by q2, 1 visible, 2 shielded) and q2 / L in kr; a point between two key points of its loop
    (rows n0[i], n1[i], points p0[i], p1[i], weight wgt[i] of the second) takes a source's verdict
    from them when both agree (-1 and 0 count as one verdict: negligible) and the two key points
    subtend at most the coherence angle at the source, q2 / L interpolated; only the other pairs
    are decided by the passes.
    """
    m = o.shape[0]
    xi = x[i]
    bv = (node_box, node_child, node_start, node_count, tri, tri_vertex, tri_normal, scale)
    gr = (g_origin, g_cell, g_dims, g_lattice)
    plain = xgrp[i] == NO_GROUP and xwin[i] < 0  # no source excluded: the loops below skip the tests
    x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
    best, bj = _nearest_admissible(i, x, xgrp, xloop, xpos, xwin, o, sgrp, sloop, spos, slen, plain)
    # pass 2: the candidates, pruned relative to the nearest source:
    # (L * shrink)^2 - best > prune2, shrink = 1 / (1 + G(0)) in full mode with free points
    cand = np.empty(m, dtype=np.int64)
    cl2 = np.empty(m)  # squared distances of the candidates
    nc = 0
    row = krow[i]
    if row >= 0:
        for j in range(m):
            kv[row, j] = -2  # excluded
    g, lo, ps, xw = xgrp[i], xloop[i], xpos[i], xwin[i]
    for j in range(m):
        if not plain and _excluded(j, g, lo, ps, xw, sgrp, sloop, spos, slen):
            continue
        r0 = o[j, 0] - x0
        r1 = o[j, 1] - x1
        r2 = o[j, 2] - x2
        l2 = r0 * r0 + r1 * r1 + r2 * r2
        if l2 * shrink2 - best > prune2 or l2 < 1e-300:
            if row >= 0:
                kv[row, j] = -1  # negligible whatever the free points
            continue
        cand[nc] = j
        cl2[nc] = l2
        nc += 1
    vis = np.ones(nc, dtype=np.bool_)
    ratio = np.ones(nc)
    lim = best + prune2  # q2^2 beyond this: weight below exp(-16) of the nearest source's
    stack = np.empty(64, dtype=np.int64)  # BVH traversal scratch, once per point
    work = np.empty((2, 3))
    istack = np.empty(128, dtype=np.int64)  # bisection intervals
    sel = np.empty(nc, dtype=np.int64)
    ns = 0
    ra, rb = n0[i], n1[i]
    dab = np.sqrt(_d2(x[p0[i]], x[p1[i]])) if ra >= 0 else 0.0
    da, db = (np.sqrt(_d2(xi, x[p0[i]])), np.sqrt(_d2(xi, x[p1[i]]))) if ra >= 0 else (0.0, 0.0)
    # coherence across points, when X lies near the chord of its two key points Xa, Xb (not at a
    # sharp corner of the loop between them): |X - Xa| + |X - Xb| <= CHORD_SLACK |Xa - Xb|
    if ra >= 0 and (use_fp or shield) and da + db <= CHORD_SLACK * dab:
        # Xa, Xb subtend at most the coherence angle theta at a source O when
        # |Xa - Xb| <= sin(theta) min(|O - Xa|, |O - Xb|) (law of sines), which holds when
        # |O - X| >= |Xa - Xb| (1 / sin(theta) + CHORD_SLACK), as |O - Xa| >= |O - X| - |X - Xa|
        w = wgt[i]
        sin_t = np.sqrt(1.0 - cos2)
        thr2 = (dab * (1.0 / sin_t + CHORD_SLACK)) ** 2
        for c in range(nc):
            j = cand[c]
            va = _verdict_class(kv[ra, j])
            vb = _verdict_class(kv[rb, j])
            if va >= 0 and va == vb and cl2[c] >= thr2:
                vis[c] = va == 1
                ratio[c] = kr[ra, j] * (1.0 - w) + kr[rb, j] * w
            else:
                sel[ns] = c
                ns += 1
    else:
        for c in range(nc):
            sel[c] = c
        ns = nc
    if use_fp:  # (4): q2 / L, and the pairs still negligible after the free points are dropped
        _q2_pass(xi, cand, sel, ns, o, sloop, vis, ratio, stride, cos2, gr, lim)
    if row >= 0:
        for t in range(ns):
            if not vis[sel[t]]:
                kv[row, cand[sel[t]]] = 0  # pruned by q2
    if shield:  # (15) for the pairs kept
        nk = 0
        for t in range(ns):
            if vis[sel[t]]:
                sel[nk] = sel[t]
                nk += 1
        _shield_pass(xi, xv[i], cand, sel, nk, o, ov, sloop, vis, stride, cos2, bv, stack, work, istack)
        ns = nk
    if row >= 0:
        for t in range(ns):
            c = sel[t]
            j = cand[c]
            if kv[row, j] != 0:
                kv[row, j] = 1 if vis[c] else 2
                kr[row, j] = ratio[c]
    h00 = h01 = h02 = h10 = h11 = h12 = h20 = h21 = h22 = 0.0  # scalars: kept in registers
    for c in range(nc):
        if not vis[c]:
            continue  # (15) delta_XO = 0
        j = cand[c]
        r0 = o[j, 0] - x[i, 0]
        r1 = o[j, 1] - x[i, 1]
        r2 = o[j, 2] - x[i, 2]
        l2 = r0 * r0 + r1 * r1 + r2 * r2
        length = np.sqrt(l2)
        il = 1.0 / length
        d0, d1, d2 = r0 * il, r1 * il, r2 * il  # (6)
        t0, t1, t2 = tau[j, 0], tau[j, 1], tau[j, 2]
        s0 = t1 * d2 - t2 * d1  # s_O = tau_O x d
        s1 = t2 * d0 - t0 * d2
        s2 = t0 * d1 - t1 * d0
        q4 = 0.5 * (1.0 - (d0 * b[j, 0] + d1 * b[j, 1] + d2 * b[j, 2]))  # (7)
        q2 = ratio[c] * length  # (4); = L without free points
        q12 = _q1(q2 * q2, lc2, kernel)  # (8)
        w = h[j] * q12 * (1.0 + ki * q4)  # (13)
        wd0, wd1, wd2 = w * d0, w * d1, w * d2  # (12)-(14): h g d s^T
        h00 += wd0 * s0
        h01 += wd0 * s1
        h02 += wd0 * s2
        h10 += wd1 * s0
        h11 += wd1 * s1
        h12 += wd1 * s2
        h20 += wd2 * s0
        h21 += wd2 * s1
        h22 += wd2 * s2
    out_h[i, 0], out_h[i, 1], out_h[i, 2] = h00, h01, h02
    out_h[i, 3], out_h[i, 4], out_h[i, 5] = h10, h11, h12
    out_h[i, 6], out_h[i, 7], out_h[i, 8] = h20, h21, h22
    out_near[i] = bj
    out_dist[i] = np.sqrt(best) if bj >= 0 else np.inf
    out_pairs[i] = nc


@numba.njit(cache=True, parallel=True)
def _field_full(x, xv, xgrp, xloop, xpos, xwin, o, ov, tau, b, h, sgrp, sloop, spos, slen,
                lc2, ki, kernel, prune2, shrink2, stride, cos2,
                shield, node_box, node_child, node_start, node_count, tri, tri_vertex, tri_normal,
                scale,
                use_fp, g_origin, g_cell, g_dims, g_lattice,
                krow, n0, n1, p0, p1, wgt, kv, kr, sub,
                out_h, out_near, out_dist, out_pairs):
    for s in numba.prange(len(sub)):
        i = sub[s]
        _full_point(i, x, xv, xgrp, xloop, xpos, xwin, o, ov, tau, b, h, sgrp, sloop, spos, slen,
                    lc2, ki, kernel, prune2, shrink2, stride, cos2,
                    shield, node_box, node_child, node_start, node_count, tri, tri_vertex, tri_normal,
                    scale,
                    use_fp, g_origin, g_cell, g_dims, g_lattice,
                    krow, n0, n1, p0, p1, wgt, kv, kr,
                    out_h, out_near, out_dist, out_pairs)


@numba.njit(cache=True)
def _field_full_serial(x, xv, xgrp, xloop, xpos, xwin, o, ov, tau, b, h, sgrp, sloop, spos, slen,
                       lc2, ki, kernel, prune2, shrink2, stride, cos2,
                       shield, node_box, node_child, node_start, node_count, tri, tri_vertex, tri_normal,
                       scale,
                       use_fp, g_origin, g_cell, g_dims, g_lattice,
                       krow, n0, n1, p0, p1, wgt, kv, kr, sub,
                       out_h, out_near, out_dist, out_pairs):
    for s in range(len(sub)):
        i = sub[s]
        _full_point(i, x, xv, xgrp, xloop, xpos, xwin, o, ov, tau, b, h, sgrp, sloop, spos, slen,
                    lc2, ki, kernel, prune2, shrink2, stride, cos2,
                    shield, node_box, node_child, node_start, node_count, tri, tri_vertex, tri_normal,
                    scale,
                    use_fp, g_origin, g_cell, g_dims, g_lattice,
                    krow, n0, n1, p0, p1, wgt, kv, kr,
                    out_h, out_near, out_dist, out_pairs)


@dataclass(frozen=True)
class Evaluation:
    """The field at N points: H (N, 3, 3); nearest (N,) index of the nearest admissible source
    (-1 if none) and its distance; pairs: point x source pairs evaluated (after pruning)."""

    H: Arr
    nearest: NDArray[np.int64]
    distance: Arr
    pairs: int


def top_normal(H: Arr, t: Arr, hint: Arr | None = None) -> tuple[Arr, Arr]:
    """(16a)/(16b): n maximising |H n| with |n| = 1 and n . t = 0: the eigenvector of the largest
    eigenvalue of P H^T H P, P = I - t t^T. Batched: H (N, 3, 3), t (N, 3), hint (N, 3) or None.

    Sign rule (spec choice): n . hint > 0 (hint = n_O at an origin, the previous normal along a
    line). Returns (n (N, 3), |H n| (N,)).
    """
    H = np.asarray(H, dtype=np.float64).reshape(-1, 3, 3)
    t = np.asarray(t, dtype=np.float64).reshape(-1, 3)
    tn = np.linalg.norm(t, axis=1, keepdims=True)
    t = np.divide(t, tn, out=np.zeros_like(t), where=tn > 0)
    P = np.eye(3)[None] - t[:, :, None] * t[:, None, :]
    HP = H @ P
    M = np.swapaxes(HP, 1, 2) @ HP
    _, vec = np.linalg.eigh(M)
    n = vec[:, :, 2]
    n = n - (n * t).sum(axis=1, keepdims=True) * t  # exact orthogonality against round-off
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    if hint is not None:
        hint = np.asarray(hint, dtype=np.float64).reshape(-1, 3)
        flip = (n * hint).sum(axis=1) < 0
        n[flip] *= -1
    f = np.einsum("nij,nj->ni", H, n)
    return n, np.linalg.norm(f, axis=1)


@numba.njit(cache=True)
def _normal_one(hm, t, hint):
    """(16b) for one point in closed form: with e1, e2 an orthonormal basis of the plane normal
    to t, |H n|^2 for n = cos(phi) e1 + sin(phi) e2 is a 2x2 quadratic form [[a, b], [b, c]]
    whose top eigenvector has phi = atan2(2 b, a - c) / 2 (the same n as the top eigenvector of
    P H^T H P). Sign n . hint >= 0. Returns (n, H n)."""
    tn = np.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
    if not tn > 0.0:  # no direction (a line's target on its last point): unconstrained, as top_normal
        _, vec = np.linalg.eigh(hm.T @ hm)  # with t = 0 (P = I): the top eigenvector of H^T H
        n = vec[:, 2].copy()
        if n[0] * hint[0] + n[1] * hint[1] + n[2] * hint[2] < 0:
            n = -n
        return n, hm @ n
    t0, t1, t2 = t[0] / tn, t[1] / tn, t[2] / tn
    if abs(t0) < 0.9:  # e1 = unit(t x x_axis) or unit(t x y_axis)
        e0, e1_, e2_ = 0.0, t2, -t1
    else:
        e0, e1_, e2_ = -t2, 0.0, t0
    en = np.sqrt(e0 * e0 + e1_ * e1_ + e2_ * e2_)
    e0, e1_, e2_ = e0 / en, e1_ / en, e2_ / en
    f0, f1, f2 = t1 * e2_ - t2 * e1_, t2 * e0 - t0 * e2_, t0 * e1_ - t1 * e0  # e2 = t x e1
    u0 = hm[0, 0] * e0 + hm[0, 1] * e1_ + hm[0, 2] * e2_
    u1 = hm[1, 0] * e0 + hm[1, 1] * e1_ + hm[1, 2] * e2_
    u2 = hm[2, 0] * e0 + hm[2, 1] * e1_ + hm[2, 2] * e2_
    v0 = hm[0, 0] * f0 + hm[0, 1] * f1 + hm[0, 2] * f2
    v1 = hm[1, 0] * f0 + hm[1, 1] * f1 + hm[1, 2] * f2
    v2 = hm[2, 0] * f0 + hm[2, 1] * f1 + hm[2, 2] * f2
    a = u0 * u0 + u1 * u1 + u2 * u2
    b = u0 * v0 + u1 * v1 + u2 * v2
    c = v0 * v0 + v1 * v1 + v2 * v2
    phi = 0.5 * np.arctan2(2.0 * b, a - c)
    cp, sp = np.cos(phi), np.sin(phi)
    n = np.empty(3)
    n[0], n[1], n[2] = cp * e0 + sp * f0, cp * e1_ + sp * f1, cp * e2_ + sp * f2
    if n[0] * hint[0] + n[1] * hint[1] + n[2] * hint[2] < 0:
        n[0], n[1], n[2] = -n[0], -n[1], -n[2]
    f = np.empty(3)
    for k in range(3):
        f[k] = hm[k, 0] * n[0] + hm[k, 1] * n[1] + hm[k, 2] * n[2]
    return n, f


@numba.njit(cache=True, fastmath=True)
def _h_one_light(x, o, tau, b, h, lc2, ki, kernel, prune2):
    """Light-mode H at one point against every source (no exclusions): the tracing step."""
    m = o.shape[0]
    x0, x1, x2 = x[0], x[1], x[2]
    best = 1e300
    for j in range(m):
        r0 = o[j, 0] - x0
        r1 = o[j, 1] - x1
        r2 = o[j, 2] - x2
        l2 = r0 * r0 + r1 * r1 + r2 * r2
        best = min(best, l2)
    lim = best + prune2
    hm = np.zeros((3, 3))
    for j in range(m):
        r0 = o[j, 0] - x0
        r1 = o[j, 1] - x1
        r2 = o[j, 2] - x2
        l2 = r0 * r0 + r1 * r1 + r2 * r2
        if l2 > lim or l2 < 1e-300:
            continue
        il = 1.0 / np.sqrt(l2)
        d0, d1, d2 = r0 * il, r1 * il, r2 * il  # (6)
        t0, t1, t2 = tau[j, 0], tau[j, 1], tau[j, 2]
        s0 = t1 * d2 - t2 * d1  # s_O = tau_O x d
        s1 = t2 * d0 - t0 * d2
        s2 = t0 * d1 - t1 * d0
        q4 = 0.5 * (1.0 - (d0 * b[j, 0] + d1 * b[j, 1] + d2 * b[j, 2]))  # (7)
        w = h[j] * _q1(l2, lc2, kernel) * (1.0 + ki * q4)  # (13)
        hm[0, 0] += w * d0 * s0  # (12)-(14)
        hm[0, 1] += w * d0 * s1
        hm[0, 2] += w * d0 * s2
        hm[1, 0] += w * d1 * s0
        hm[1, 1] += w * d1 * s1
        hm[1, 2] += w * d1 * s2
        hm[2, 0] += w * d2 * s0
        hm[2, 1] += w * d2 * s1
        hm[2, 2] += w * d2 * s2
    return hm


@numba.njit(cache=True)
def _sample_light(x, t, hint, o, tau, b, h, lc2, ki, kernel, prune2):
    """One tracing step in light mode: H, then n from (16b) and F = H n, in one call."""
    hm = _h_one_light(x, o, tau, b, h, lc2, ki, kernel, prune2)
    return _normal_one(hm, t, hint)


class IndicatorField:
    """BIAF over a set of sources (the field of §4) with the parameters' mode.

    lc: L_c (already resolved). mesh_bvh: the island triangles for shielding (full mode).
    free: the free points (full mode). Evaluations go through `evaluate` in chunks of ``chunk``
    points (the kernels allocate nothing per pair, so memory is O(chunk + M)).
    """

    def __init__(self, sources: Sources, params: FieldParams, lc: float, *, bvh: Bvh | None = None,
                 free: FreePoints | None = None, chunk: int = 4096) -> None:
        if not lc > 0:
            raise ValueError(f"L_c must be positive, not {lc}")
        self.sources = sources
        self.params = params
        self.lc = float(lc)
        self.bvh = bvh
        self.free = free if (free is not None and len(free.points) and params.use_free_points) else None
        self.shield = bool(params.shielding and bvh is not None and bvh.n_triangles)
        self.chunk = int(chunk)
        self.kernel = 0 if params.q1_kernel == "gauss" else 1
        # pruning in full mode (choice, documented): free points may rescue a pair by the factor
        # 1 + G(0) (one fully trusted free point's worth), not by the bound 1 + max sum G, which on
        # dense free points would disable pruning altogether (measured: 12x slower, bench/field.py)
        gmax = g0(self.free.kt) if self.free is not None else 0.0
        # a Gaussian source is skipped when its weight is below exp(-16) of the nearest one's (in
        # full mode even after free points shorten it as much as they can: q2 >= L / (1 + max sum G));
        # the heavy-tailed kernel is never pruned.
        self.prune = PRUNE_GAUSS * self.lc if self.kernel == 0 else np.inf
        self.shrink = 1.0 / (1.0 + gmax)
        self._prune2 = float(prune_bound2(self.lc, self.kernel))
        self._one: tuple | None = None  # full mode, one point: the kernel's arguments, made once

    def _full_args(self) -> tuple:
        """The arguments of _field_full after the points' own arrays (sources, parameters, BVH,
        lattice), up to the coherence-across-points arrays."""
        S, p, bvh = self.sources, self.params, self.bvh
        barr = bvh.arrays() if bvh is not None else _EMPTY_BVH
        garr = lattice_args(self.free) if self.free is not None else _EMPTY_GRID
        return (S.points, S.vertex, S.tangent, S.outward, S.charge, S.group, S.loop, S.pos, S.loop_len,
                self.lc * self.lc, float(p.ki), self.kernel, self._prune2, self.shrink ** 2, int(p.shield_stride),
                float(np.cos(np.radians(p.coherence_deg)) ** 2), self.shield, *barr,
                bvh.scale if bvh is not None else 1.0, self.free is not None, *garr)

    def one_point_args(self) -> tuple:
        """The arguments of _field_full_serial for one point with no exclusions (a tracing step),
        up to the outputs; made once."""
        if self._one is None:
            one = np.full(1, -1, dtype=np.int64)
            pts = (one, np.full(1, NO_GROUP, dtype=np.int64), one, np.zeros(1, dtype=np.int64), one)
            coh = (one, one, one, np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64), np.zeros(1),
                   np.zeros((0, len(self.sources)), dtype=np.int8), np.zeros((0, len(self.sources))),
                   np.zeros(1, dtype=np.int64))
            self._one = (*pts, *self._full_args(), *coh)
        return self._one

    def _full_one(self, x: Arr) -> Arr:
        """Full-mode H (3, 3) at one point, no exclusions, no per-call set-up (a tracing step)."""
        H = np.zeros((1, 9))
        _field_full_serial(np.asarray(x, dtype=np.float64).reshape(1, 3), *self.one_point_args(), H,
                           np.zeros(1, dtype=np.int64), np.zeros(1), np.zeros(1, dtype=np.int64))
        return H.reshape(3, 3)

    def sample_one(self, x: Arr, tangent: Arr, hint: Arr) -> tuple[Arr, Arr, float]:
        """One point, no exclusions (a tracing step): (n, F = H n, |F|) with n from (16b)."""
        if not self.full:
            S = self.sources
            if len(S) == 0:
                return np.asarray(hint, dtype=np.float64), np.zeros(3), 0.0
            n, f = _sample_light(np.asarray(x, dtype=np.float64), np.asarray(tangent, dtype=np.float64),
                                 np.asarray(hint, dtype=np.float64), S.points, S.tangent, S.outward, S.charge,
                                 self.lc * self.lc, float(self.params.ki), self.kernel, self._prune2)
            return n, f, float(np.sqrt(f @ f))
        if len(self.sources) == 0:
            return np.asarray(hint, dtype=np.float64), np.zeros(3), 0.0
        n, f = _normal_one(self._full_one(x), np.asarray(tangent, dtype=np.float64), np.asarray(hint, dtype=np.float64))
        return n, f, float(np.sqrt(f @ f))

    @property
    def full(self) -> bool:
        return self.params.mode == "full"

    def evaluate(self, x: Arr, *, x_vertex: NDArray[np.int64] | None = None, x_group: NDArray[np.int64] | None = None,
                 x_loop: NDArray[np.int64] | None = None, x_pos: NDArray[np.int64] | None = None,
                 x_window: NDArray[np.int64] | None = None, x_lc: Arr | None = None) -> Evaluation:
        """H(X) at points x (N, 3). x_group: sources of that group are excluded for each point;
        x_loop / x_pos / x_window: sources of the same loop within x_window positions of x_pos are
        excluded (-1 = no window); in full mode they also say which points are consecutive along a
        loop (coherence across points, FieldParams.point_stride). x_vertex: the mesh vertex each
        point is (shielding ignores its triangles; -1 for a free point). x_lc: (N,) L_c per point,
        light mode only (points of several loops, each with its own L_c, in one call: the same H
        as one call per L_c); None = the field's L_c."""
        x = np.ascontiguousarray(np.asarray(x, dtype=np.float64).reshape(-1, 3))
        n = len(x)
        if x_lc is not None and self.full:
            raise ValueError("x_lc (an L_c per point) is for light mode only: full mode's free points and "
                             "pruning depend on L_c")

        def ints(a, fill):
            return np.full(n, fill, dtype=np.int64) if a is None else np.ascontiguousarray(a, dtype=np.int64)

        xv, xg = ints(x_vertex, -1), ints(x_group, NO_GROUP)
        xl, xp, xw = ints(x_loop, -1), ints(x_pos, 0), ints(x_window, -1)
        S = self.sources
        H = np.zeros((n, 9))
        near = np.full(n, -1, dtype=np.int64)
        dist = np.full(n, np.inf)
        pairs = 0
        if not self.full:  # the light kernels read L_c^2 and the pruning bound per point
            lc_pt = np.full(n, self.lc) if x_lc is None else np.ascontiguousarray(x_lc, dtype=np.float64).reshape(n)
            if not np.all(lc_pt > 0):
                raise ValueError("x_lc: L_c must be positive")
            lc2_pt, prune2_pt = lc_pt * lc_pt, prune_bound2(lc_pt, self.kernel)
        p = self.params
        if n == 0 or len(S) == 0:
            return Evaluation(H.reshape(n, 3, 3), near, dist, 0)
        chunk = self.chunk
        if self.full:  # the key points' verdicts take 9 bytes per key point x source: at most KEY_MEMORY
            chunk = min(chunk, max(256, KEY_MEMORY // (9 * len(S)) * int(p.point_stride)))
        for a in range(0, n, chunk):
            sl = slice(a, min(a + chunk, n))
            if not self.full:
                lk: Any = _field_light if sl.stop - sl.start >= SERIAL_BELOW else _field_light_serial
                lk(x[sl], xg[sl], xl[sl], xp[sl], xw[sl], S.points, S.tangent, S.outward, S.charge, S.group,
                   S.loop, S.pos, S.loop_len, lc2_pt[sl], p.ki, self.kernel, prune2_pt[sl], H[sl], near[sl],
                   dist[sl])
                pairs += (sl.stop - sl.start) * len(S)
            else:
                args = self._full_args()
                nn = sl.stop - sl.start
                cnt = np.zeros(nn, dtype=np.int64)
                coh = key_points(xl[sl], xp[sl], int(p.point_stride) if (self.shield or self.free) else 1)
                krow, n0, n1, p0, p1, wgt, keys, rest = coh
                kv = np.empty((len(keys) if n0.max(initial=-1) >= 0 else 0, len(S)), dtype=np.int8)
                kr = np.empty(kv.shape)
                fk: Any = _field_full if nn >= SERIAL_BELOW else _field_full_serial
                for sub in (keys, rest):  # the key points first: the others read their verdicts
                    if len(sub) == 0:
                        continue
                    fk(x[sl], xv[sl], xg[sl], xl[sl], xp[sl], xw[sl], *args,
                       krow if len(kv) else np.full(nn, -1, dtype=np.int64),
                       n0, n1, p0, p1, wgt, kv, kr, sub, H[sl], near[sl], dist[sl], cnt)
                pairs += int(cnt.sum())
        return Evaluation(H.reshape(n, 3, 3), near, dist, pairs)


def key_points(loop: NDArray[np.int64], pos: NDArray[np.int64], stride: int) -> tuple:
    """Coherence across points (full mode, FieldParams.point_stride): the points that are
    consecutive positions of one loop (loop[i] >= 0, pos[i] = pos[i - 1] + 1) form runs; in each
    run every stride-th point and the last are key points, decided pair by pair; each other
    point lies between two key points of its run. Returns (krow: row of each key point or -1,
    n0, n1: rows of the two key points around each other point (-1 for key points), p0, p1: their
    point indices, wgt: the second one's interpolation weight, keys, rest: point indices)."""
    n = len(loop)
    krow = np.full(n, -1, dtype=np.int64)
    n0 = np.full(n, -1, dtype=np.int64)
    n1 = np.full(n, -1, dtype=np.int64)
    p0 = np.zeros(n, dtype=np.int64)
    p1 = np.zeros(n, dtype=np.int64)
    wgt = np.zeros(n)
    if stride <= 1 or n < 3:
        return krow, n0, n1, p0, p1, wgt, np.arange(n, dtype=np.int64), np.zeros(0, dtype=np.int64)
    cont = np.zeros(n, dtype=bool)
    cont[1:] = (loop[1:] >= 0) & (loop[1:] == loop[:-1]) & (pos[1:] == pos[:-1] + 1)
    start = np.maximum.accumulate(np.where(~cont, np.arange(n), 0))  # first point of each one's run
    end = np.zeros(n, dtype=bool)
    end[:-1] = ~cont[1:]
    end[-1] = True
    key = ((np.arange(n) - start) % stride == 0) | end
    keys = np.flatnonzero(key)
    krow[keys] = np.arange(len(keys))
    rest = np.flatnonzero(~key)
    k = np.searchsorted(keys, rest)  # keys[k - 1] < i < keys[k], both in i's run (its start and end are keys)
    a, b = keys[k - 1], keys[k]
    p0[rest], p1[rest] = a, b
    n0[rest], n1[rest] = krow[a], krow[b]
    wgt[rest] = (rest - a) / (b - a)
    return krow, n0, n1, p0, p1, wgt, keys, rest


_EMPTY_BVH = (np.zeros((0, 6)), np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64),
              np.zeros(0, dtype=np.int64), np.zeros((0, 3, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3)))
_EMPTY_GRID = (np.zeros(3), 1.0, np.ones(3, dtype=np.int64), np.zeros(1))


def direct_tensor(x: Arr, sources: Sources, params: FieldParams, lc: float) -> Arr:
    """Reference H(X) by a plain loop over sources with quality.basic_task (light mode, for tests)."""
    from .quality import basic_task

    H = np.zeros((3, 3))
    for j in range(len(sources)):
        o = sources.points[j]
        if np.linalg.norm(o - x) == 0:
            continue
        # H_O = h g d s_O^T: read it off column by column with n_X = e_k, since f = d h Q(n_X)
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1.0
            f = basic_task(x, e, o, sources.tangent[j], sources.normal[j], params, lc)
            H[:, k] += f["d"] * sources.charge[j] * f["Q10"]  # (11) f = d h Q
    return H

"""The tracers (spec/repair.md §5: simple, 2004; predictor-corrector, 2010 F4.1) fused into one
numba loop for the BIAF (light mode, and full mode with shielding and free points). The module
keeps its name from when it served light mode only.

force_lines.trace runs the same steps in Python against any field of the protocol; with a
light-mode IndicatorField each step there costs ~150 us of Python (sample -> evaluate -> normal
-> a k-d tree query for the targets and one for the avoid points) around ~20 us of arithmetic.
Here a chunk of steps runs without leaving numba: H at the new point (12)-(14), its normal (16b),
the target hit test (the 4 nearest targets, the nearest within its reach: force_lines.Targets.hit)
and the turned-back test (nearest avoid point within one step) by brute force over the points,
O(T) per step like the field itself (O(M) per step). The arithmetic is the Python tracer's, in
the same order, so a line is the same line (tests/test_force_lines.py compares both).
"""

from __future__ import annotations

import numba
import numpy as np

from .indicator import _field_full_serial, _normal_one, _sample_light

CONTINUE, ARRIVED_C, TURNED_BACK_C, TOO_WEAK_C, STALLED_C, STEP_LIMIT_C = 0, 1, 2, 3, 4, 5


@numba.njit(cache=True)
def target_hit(x, tg, reach):
    """Index of the nearest target within its reach of x among the 4 nearest targets, or -1
    (force_lines.Targets.hit by brute force)."""
    kk = min(4, tg.shape[0])
    bd = np.full(4, np.inf)
    bi = np.full(4, -1, dtype=np.int64)
    for j in range(tg.shape[0]):
        r0 = tg[j, 0] - x[0]
        r1 = tg[j, 1] - x[1]
        r2 = tg[j, 2] - x[2]
        d2 = r0 * r0 + r1 * r1 + r2 * r2
        if d2 < bd[kk - 1]:  # insert into the sorted list of the kk nearest
            q = kk - 1
            while q > 0 and bd[q - 1] > d2:
                bd[q] = bd[q - 1]
                bi[q] = bi[q - 1]
                q -= 1
            bd[q] = d2
            bi[q] = j
    for q in range(kk):
        if bi[q] >= 0 and np.sqrt(bd[q]) < reach[bi[q]]:
            return bi[q]
    return -1


@numba.njit(cache=True)
def _near_any(x, pts, radius):
    """Is some point of pts (K, 3) closer than radius to x?"""
    r2max = radius * radius
    for j in range(pts.shape[0]):
        r0 = pts[j, 0] - x[0]
        r1 = pts[j, 1] - x[1]
        r2 = pts[j, 2] - x[2]
        if r0 * r0 + r1 * r1 + r2 * r2 < r2max:
            return True
    return False


@numba.njit(cache=True)
def _sample(x, t, hint, full, la, fa):
    """(n, F = H n) at x with n from (16b) (n . t = 0, n . hint >= 0): light mode from la (the
    arguments of _sample_light after (x, t, hint)), full mode from fa (IndicatorField.one_point_args:
    shielding and free points for one point, as IndicatorField.sample_one)."""
    if full:
        hm = np.zeros((1, 9))
        _field_full_serial(x.reshape((1, 3)), *fa, hm, np.zeros(1, dtype=np.int64), np.zeros(1),
                           np.zeros(1, dtype=np.int64))
        return _normal_one(hm.reshape((3, 3)), t, hint)
    return _sample_light(x, t, hint, la[0], la[1], la[2], la[3], la[4], la[5], la[6], la[7])


@numba.njit(cache=True)
def _corrected(x, p, n, step, dev, offs, full, la, fa):
    """2010 F4.1: the predictor P1' = X + s p, its normal N1' (16b), and among the points
    P1' + (d o) N1' (o in offs) the one of maximum potential |H n| (the first one on ties; at
    o = 0 the predictor's own tension), as force_lines.trace's Python loop does."""
    pred = x + step * p
    n1, f1 = _sample(pred, p, n, full, la, fa)
    zero = np.zeros(3)
    best = -1.0
    out = pred
    for q in range(offs.shape[0]):
        c = pred + (dev * offs[q]) * n1
        if abs(offs[q]) < 1e-12:
            psi = np.sqrt(f1[0] * f1[0] + f1[1] * f1[1] + f1[2] * f1[2])
        else:
            _, fc = _sample(c, p, zero, full, la, fa)
            psi = np.sqrt(fc[0] * fc[0] + fc[1] * fc[1] + fc[2] * fc[2])
        if psi > best:
            best = psi
            out = c
    return out


@numba.njit(cache=True)
def tracer_chunk(state, start, n_rec, max_steps, chunk, step, floor, full, la, fa,
                 tg, reach, avoid, out_x, out_n, out_f, out_t, pc, dev, offs):
    """Up to `chunk` steps of the simple tracer X_{k+1} = X_k + s F_k / |F_k| (pc False) or of the
    predictor-corrector (pc True: deviation dev, offsets offs along the predicted normal), with n
    from (16b) at each new point, in the BIAF of la (light mode) or fa (full mode, full True).

    state (3, 3): rows x, F, n of the last recorded point (updated in place); n_rec: points
    recorded so far. Writes the new points, normals, forces, tensions into out_*; returns
    (points written, status code, target hit or -1)."""
    x = state[0].copy()
    f = state[1].copy()
    n = state[2].copy()
    k = 0
    while True:
        if n_rec + k >= max_steps:
            return k, STEP_LIMIT_C, -1
        if k >= chunk:
            state[0], state[1], state[2] = x, f, n
            return k, CONTINUE, -1
        fn = np.sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])
        if not fn > 0.0:  # no force (a target on the point itself): no direction to step in
            state[0], state[1], state[2] = x, f, n
            return k, TOO_WEAK_C, -1
        p = f / fn
        if pc:  # 2010 F4.1
            x_new = _corrected(x, p, n, step, dev, offs, full, la, fa)
        else:
            x_new = x + step * p  # 2004: X_{k+1} = X_k + s F_k / |F_k|
        tang = x_new - x
        tang /= max(np.sqrt(tang[0] * tang[0] + tang[1] * tang[1] + tang[2] * tang[2]), 1e-300)
        sn, sf = _sample(x_new, tang, n, full, la, fa)  # (16b)
        x_prev = x
        x = x_new
        hit = target_hit(x, tg, reach)
        if hit >= 0:  # the line ends on the target point
            end = tg[hit].copy()
            ne, fe = _sample(end, end - x_prev, n, full, la, fa)
            out_x[k], out_n[k], out_f[k] = end, ne, fe
            out_t[k] = np.sqrt(fe[0] * fe[0] + fe[1] * fe[1] + fe[2] * fe[2])
            return k + 1, ARRIVED_C, hit
        tension = np.sqrt(sf[0] * sf[0] + sf[1] * sf[1] + sf[2] * sf[2])
        out_x[k], out_n[k], out_f[k] = x, sn, sf
        out_t[k] = tension
        k += 1
        if avoid.shape[0]:
            dx = x - start
            if dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2] > 4 * step * step and _near_any(x, avoid, step):
                return k, TURNED_BACK_C, -1
        if tension < floor or tension <= 0:
            return k, TOO_WEAK_C, -1
        if sf[0] * tang[0] + sf[1] * tang[1] + sf[2] * tang[2] < 0:
            return k, STALLED_C, -1
        f = sf
        n = sn

"""The RBF implicit of a smooth hole's rings (implicit.py), where the APSS (apss.py) and the fairing
disagree about its fill.

The APSS projection (apss.py) moves a faired fill vertex onto a sphere fitted to the input points
read around it when the two disagree by more than a fraction of an edge: across a thin part or a
concave fold the fairing spans a chord and the sphere is right. But a vertex a few edges into a
broad hole reads the input on one side of it only, and the sphere fitted there, extrapolated
across those edges, can be worse than the fairing: on the closed bunny cut by 25 balls of radius
4 % of the diagonal (unseen case u-bunny-25), the APSS dented a hole on the back by 1.0 % of the
diagonal where the faired fill was within 0.37 % of the truth (and 0.58 / 0.90 %, 0.23 / 0.49 %
on two more holes); per point measures (which side of the sphere, how one-sided the data read)
did not tell the good moves from the bad.

The r^3 RBF implicit of the hole's whole surroundings (Carr et al. 2001, implicit.fit_rbf: the
input vertices within ``rings`` rings of the loop, at most ``max_points`` of them, off-surface
points at ``offset`` edge lengths along the normals of every ``stride``-th point) reads every side
of the hole at once; its zero set continues the surface through the hole with the smoothest
(triharmonic) interpolant, and follows a concave fold where the fairing cut across it. On
u-bunny-25 the holes the APSS moved, per hole max |distance| to the truth, % of the diagonal:
fairing / APSS / RBF 0.37 / 1.00 / 0.57, 0.70 / 0.89 / 0.75, 0.58 / 0.90 / 0.57, 1.24 / 0.85 / 0.50
(the fold), 0.74 / 0.74 / 0.55 (200 points). (choice) rings 3, 150 points, stride 3, offset 0.5:
with 100 points the dented hole stayed at 0.80 %, with offset 2 at 0.81 %; 150 points fit in a
third of the time of 200 (15 against 40 ms), u-bunny-25 the same (0.96 %).

But the RBF is not always right either: on a 6-7 % hole of bunny-holes it bulged out to 1.17 %
where the fairing was at 0.51 % and the APSS at 0.67 %. Three guesses, none reliable alone: each
fill vertex takes their median (median_move), along the APSS move. Per hole as above, median:
0.57, 0.75, 0.57, 0.69, 0.74; on bunny-holes' hole 0.67. (choice) Only holes where the APSS moved
a vertex by more than ``doubt`` = half an edge length are judged (an RBF fit costs 10-20 ms; on the
bunny cut into 60 holes, 3 holes instead of 25 with any move, its Hausdorff 0.76 -> 0.63 %). At one
edge, a hole the APSS moved by 0.86 edge went unjudged: 1.65 % of the diagonal off on a cut of the
F-rep 'perturbed' object where the fairing was at 0.3 % (0.45 % judged); on 80 random cuts of the
four F-rep demo objects, eight runs improved (max 1.66 -> 1.09 %), none got worse; on the
random-cut sweep (bench/sweep.py, 760 runs) 22 improved (torus 5:1 1.15 -> 0.09 %) and one got
worse (annulus 7:0 full 0.72 -> 1.16 %, flat rings where the RBF rounds); the bench cases did not
change. The
re-projection after the tangential relaxation keeps the APSS for the vertices that took its whole
move, the others stay where the median put them (the relaxation moves them along the surface).

A hole qualifies when at least ``surrounded`` of its loop is input border (beyond bridge chains
the surface is missing: the implicit would extrapolate into it) and the input normals around it do
not face opposite ways (a hole across a thin part is the thin-tip RBF's, repair._thin_tips).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .implicit import RBFImplicit, fit_rings, opposite_normals


def smooth_hole_fits(V: NDArray[np.float64], V_apss: NDArray[np.float64], F_in: NDArray[np.int64], n_input: int,
                     N: NDArray[np.float64], loops: list, patches: list[NDArray[np.int64]], spacing: float, *,
                     doubt: float = 0.5, rings: int = 3, max_points: int = 150, stride: int = 3, offset: float = 0.5,
                     surrounded: float = 0.85) -> list[tuple[RBFImplicit, NDArray[np.int64], float]]:
    """(RBF implicit, fill vertices, reach) of each hole where the APSS moved one of its fill
    vertices (``patches[k]``, the movable ones) from V to V_apss by more than ``doubt`` edge
    lengths (module docstring). ``loops``: the holes' vertex loops; V (the input's first
    ``n_input`` vertices, their unit normals N) and the input faces F_in give the rings;
    ``spacing``: the edge length l."""
    out = []
    hit = np.linalg.norm(V_apss - V, axis=1) > doubt * spacing
    for poly, which in zip(loops, patches, strict=True):
        lp = np.asarray(list(poly), dtype=np.int64)
        which = np.asarray(which, dtype=np.int64)
        if not len(which) or not hit[which].any():
            continue
        given = np.unique(lp[lp < n_input])
        if len(given) < max(4, surrounded * len(np.unique(lp))) or opposite_normals(N[given]):
            continue
        rbf = fit_rings(V, N, F_in, n_input, given, rings=rings, max_points=max_points, spacing=spacing,
                        stride=stride, offset=offset)
        if rbf is None:
            continue
        out.append((rbf, which, float(np.linalg.norm(V[lp] - V[lp].mean(axis=0), axis=1).max())))
    return out


def median_move(faired: NDArray[np.float64], apss: NDArray[np.float64],
                rbf: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The median of three guesses of each fill vertex (module docstring) along the APSS move
    d = apss - faired: 0 (the faired point), |d| (the APSS point) and (rbf - faired) . d/|d| (how
    far the RBF's point lies that way); the vertex moves by the median along d. So the APSS move
    is kept where the RBF goes at least as far the same way, shortened to the RBF's where it goes
    less far, and dropped where the RBF goes the other way; continuous in both guesses (choosing
    whole points instead left neighbours on different surfaces: min angle 22 -> 19 deg on
    u-bunny-25). Returns (the (K, 3) positions, which vertices took the whole APSS move)."""
    d = apss - faired
    a = np.linalg.norm(d, axis=1)
    u = d / np.maximum(a, 1e-300)[:, None]
    t = np.clip(np.einsum("ij,ij->i", rbf - faired, u), 0.0, a)
    return faired + t[:, None] * u, (a > 0) & (t >= a)

"""Refinement of a hole patch: centroid splitting with the edge-length scale, Delaunay edge flips
(Liepa 2003; spec/frep.md §4 "Adding vertices").

Each vertex of the hole border gets l(v), the mean length of its edges outside the patch; a
vertex made by a split gets l(v_c) = (l(v_i) + l(v_j) + l(v_k)) / 3. A patch face (v_i, v_j, v_k)
is split at its centroid v_c into three when, for every corner m,

    alpha |v_c - v_m| > l(v_c)   and   alpha |v_c - v_m| > l(v_m)                  (frep.md §4)

(alpha = ``density``; the spec's test is alpha = 1, Liepa uses sqrt 2 for a density matching the
surroundings). After the splits the patch edges are relaxed: an edge (a, b) with opposite
vertices c and d is flipped to (c, d) when d lies inside the circumcircle of (a, b, c) in the
plane of the faces, i.e. when the angles at c and d sum to more than pi (the standard Delaunay
flip test on a surface). Splitting and relaxing repeat until no face splits and no edge flips.

Only patch faces and patch-interior edges change; the fixed faces are never touched. Both steps
are vectorised over all faces / edges of a round; the rounds themselves are sequential.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..mesh import face_areas, face_cross, face_normals
from ..topology import VertexFaces, edge_table, face_adjacency, halfedges
from .flips import edge_keys_among, flip_passes
from .refine_kernels import corner_angles as _corner_angles
from .refine_kernels import grid_search, smooth_bad, unchangeable
from .split_kernels import centroid_splits, obtuse_edges

# _move_best's guards (**(choice)**): the point the search finds in the tangent plane is brought to the
# nearest point of the star's old faces (ON_STAR), and the move stands only if the angles there still beat
# the old ones and nothing folds: the vertex stays on the surface its star spans, however coarse or bent
# the star is. A vertex whose ring lies along a line (middle spread below RING_LINE of the largest) stays:
# it has no tangent plane.
# Measured: bench/sweep.py cut mushroom:5:0, a fill in the concave corner under the cap, slivers along
# the corner's ring: their normals' sum leaned sideways, and the search moved two points 0.10-0.11 off
# the surface into the cap (3.8 % of the diagonal; 0.59 % on the star's faces). A bound on the distance
# from the old faces relative to the star's reach (the guard before) let featuretype:8:1 (full) move a
# vertex of a long sliver star 0.34 off its faces: 10.4 % of the diagonal; 4.3 % on the faces
ON_STAR, RING_LINE = True, 0.1


@dataclass(frozen=True, eq=False)
class Refined:
    """vertices: (V + K, 3), the input vertices then K new ones; faces: (M, 3) the patch faces;
    label: (M,) the label of the input patch face each face came from (splits inherit it)."""

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    label: NDArray[np.int64]
    splits: int
    flips: int
    rounds: int


def edge_scale(vertices: NDArray[np.float64], fixed_faces: NDArray[np.int64], n_vertices: int) -> NDArray[np.float64]:
    """(V,) l(v): mean length of v's edges among the fixed faces (NaN where v has none)."""
    v = np.asarray(vertices, dtype=np.float64)
    e = edge_table(np.asarray(fixed_faces, dtype=np.int64)).edges if len(fixed_faces) else np.zeros((0, 2), np.int64)
    ln = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    s = np.bincount(e.ravel(), weights=np.repeat(ln, 2), minlength=n_vertices)
    c = np.bincount(e.ravel(), minlength=n_vertices)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(c > 0, s / np.maximum(c, 1), np.nan)


def relax(vertices: NDArray[np.float64], patch: NDArray[np.int64], fixed_faces: NDArray[np.int64], *,
          max_passes: int = 200, locked: NDArray[np.int64] | None = None) -> tuple[NDArray[np.int64], int]:
    """Delaunay edge flips on the patch-interior edges until none flips.

    One pass flips an independent set of violating edges at once (each face takes part in at
    most one flip: every face picks its most violating edge, an edge flips when both its faces
    picked it, so the worst edge always flips). A flip is refused when the new edge already
    exists (it would be non-manifold) or when a new face would fold over (its normal opposes the
    quad's). ``locked`` (K, 2): edges that never flip (e.g. a continued crease). Returns (faces,
    number of flips).
    """
    p = np.asarray(vertices, dtype=np.float64)
    f = np.array(patch, dtype=np.int64, copy=True).reshape(-1, 3)
    fixed = np.asarray(fixed_faces, dtype=np.int64).reshape(-1, 3)
    nv = len(p)
    # the border / locked edge keys between patch vertices (the only ones a flip can meet), compiled
    fixed_keys = edge_keys_among(f, fixed, nv, True) if len(fixed) else np.zeros(0, np.int64)
    locked_keys = (edge_keys_among(f, np.asarray(locked, dtype=np.int64).reshape(-1, 2), nv, False)
                   if locked is not None and len(locked) else np.zeros(0, np.int64))
    # the passes (the independent sets, the refusals) run compiled: flips.flip_passes
    total = int(flip_passes(p, f, fixed_keys, locked_keys, int(max_passes)))
    return f, total


def refine(vertices: NDArray[np.float64], fixed_faces: NDArray[np.int64], patch: NDArray[np.int64], *,
           density: float = np.sqrt(2.0), scale: NDArray[np.float64] | None = None, max_rounds: int = 60,
           flip: bool = True, label: NDArray[np.int64] | None = None,
           obtuse: float | None = 150.0, budget: float = 6.0, lens: float | None = None) -> Refined:
    """Refine the patch faces ``patch`` (indices into ``vertices``) next to ``fixed_faces``.

    density: alpha of the split test (1 = the spec's test literally; sqrt 2 = Liepa's).
    scale: optional (V,) l(v) to use instead of the mean fixed edge length (NaN = unknown).
    Patch vertices without a scale (no fixed edge) get the mean of the known ones.
    obtuse: **(choice)** when nothing splits or flips any more, a patch-interior edge facing an
        angle above this many degrees is split at its midpoint, and the rounds go on (a
        near-flat sliver, e.g. Liepa's zero-area ear over three almost collinear border vertices,
        passes the centroid test and no flip can remove it); None: the spec's rounds only.
    budget: **(choice)** splitting stops once the patch has more than ``budget`` times the faces
        an even triangulation at the scale l would need (patch area / (sqrt(3)/4 l^2), plus the
        initial faces): a folded or self-overlapping patch, whose flips are refused, could
        otherwise split without end.
    lens: **(choice)** Ruppert's encroachment rule for the edges that can neither split nor flip
        (the hole border, input faces being kept): a centroid or midpoint that would see such an
        edge at more than ``lens`` degrees (Shewchuk's diametral lens, 120: the triangle it would make
        on that edge has angles below 30 degrees at the edge's ends) is not inserted; the face stays
        whole (a long border edge beside short ones: the centroid of its face lies a third of the
        face's height from it, so each split brought a vertex closer and the last triangle on the
        edge had 1-4 degree angles), and only for border edges longer than ``density`` times their
        ends' scale. None (default): the spec's test alone. Measured with 120 in the repair: every
        border edge guarded, featuretype-hole unforced angles below 20 deg 20.7 -> 20.0 % but
        bunny-many-holes min angle 18.6 -> 4.1 deg; long edges only, no gain on featuretype and
        bunny-many-holes Hausdorff 0.76 -> 0.87 % of the diagonal (faces left whole): not the default.
    """
    if not density > 0:
        raise ValueError(f"density must be > 0, got {density}")
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.array(patch, dtype=np.int64, copy=True).reshape(-1, 3)
    lab = np.arange(len(f)) if label is None else np.array(label, dtype=np.int64, copy=True)
    lv = edge_scale(v, fixed_faces, len(v)) if scale is None else np.array(scale, dtype=np.float64, copy=True)
    used = np.unique(f)
    known = used[np.isfinite(lv[used])]
    fill = float(lv[known].mean()) if len(known) else float(np.mean(
        np.linalg.norm(v[f] - v[np.roll(f, 1, axis=1)], axis=2))) if len(f) else 1.0
    lv[used[~np.isfinite(lv[used])]] = fill
    pts = [v]
    nv = len(v)
    splits = flips = 0
    area = float(face_areas(v, f).sum())
    max_faces = budget * (len(f) + area / (np.sqrt(3) / 4 * fill * fill)) if fill > 0 else np.inf
    rounds = 0
    # obtuse-edge splitting rounds are capped: an obtuse angle at a vertex nearly on a long border
    # edge survives every halving of the edge across it (each midpoint as flat as the last), and
    # the midpoints would converge until they coincide
    obtuse_rounds = 0
    while rounds < max_rounds:  # sequential: split, relax, repeat (frep.md §4)
        rounds += 1
        P = np.vstack(pts) if len(pts) > 1 else pts[0]
        split, vc, lc = centroid_splits(P, f, lv, float(density))  # the test above, l(v_c) = lc
        if lens is not None and split.any():
            split[split] = ~_encroached(P, _stuck_edges(P, f, fixed_faces, lv, density), vc[split], lens=lens)
        if len(f) + 2 * int(split.sum()) > max_faces:
            split[:] = False
        ns = int(split.sum())
        if ns:
            new = nv + np.arange(ns)
            nv += ns
            pts.append(vc[split])
            lv = np.concatenate([lv, lc[split]])
            s = f[split]
            keep = f[~split]
            f = np.vstack([keep, np.stack([s[:, 0], s[:, 1], new], 1), np.stack([s[:, 1], s[:, 2], new], 1),
                           np.stack([s[:, 2], s[:, 0], new], 1)])
            lab = np.concatenate([lab[~split], np.tile(lab[split], 3)])
            splits += ns
        nflip = 0
        if flip:
            P = np.vstack(pts) if len(pts) > 1 else pts[0]
            f, nflip = relax(P, f, fixed_faces)
            flips += nflip
        if not ns and not nflip:
            if obtuse is None or len(f) > max_faces or obtuse_rounds >= 6:
                break
            obtuse_rounds += 1
            P = np.vstack(pts) if len(pts) > 1 else pts[0]
            f, lab, mids, lm = _split_obtuse(P, f, lab, lv, nv, np.radians(obtuse),
                                             _stuck_edges(P, f, fixed_faces, lv, density)
                                             if lens is not None else None,
                                             lens or 180.0)
            if not len(mids):
                break
            pts.append(mids)
            lv = np.concatenate([lv, lm])
            nv += len(mids)
            splits += len(mids)
    P = np.vstack(pts) if len(pts) > 1 else pts[0]
    return Refined(P, f, lab, splits, flips, rounds)


def _stuck_edges(p: NDArray[np.float64], f: NDArray[np.int64], fixed: NDArray[np.int64], lv: NDArray[np.float64],
                 density: float) -> NDArray[np.int64]:
    """(S, 2) the long patch edges that can neither split nor flip: edges of the fixed faces (the hole
    border) and edges with one patch face, longer than ``density`` times their ends' mean scale l
    (an edge at the scale is not guarded: the centroid of an equilateral face on it lies on its lens,
    and the spec's splits along an even border would stop: bunny-many-holes min angle 18.6 -> 4.1 deg
    with every border edge guarded)."""
    stuck = unchangeable(f, len(p), np.asarray(fixed, dtype=np.int64).reshape(-1, 3), None)
    a, b = f[stuck], np.roll(f, -1, axis=1)[stuck]
    long_ = np.linalg.norm(p[a] - p[b], axis=1) > density * (lv[a] + lv[b]) / 2
    return np.stack([a[long_], b[long_]], axis=1)


def _split_obtuse(p: NDArray[np.float64], f: NDArray[np.int64], lab: NDArray[np.int64], lv: NDArray[np.float64],
                  nv: int, limit: float, stuck: NDArray[np.int64] | None = None, lens: float = 120.0
                  ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """Split the patch-interior edges facing an angle above ``limit`` (radians) at their midpoints;
    each face takes part in at most one split; a midpoint in the diametral lens of a ``stuck`` edge
    (S, 2) is not used (refine's ``lens``). Returns (faces, labels, new points, their l)."""
    # the interior edges facing an angle above the limit and longer than half their ends' scale
    # (halving them cannot go on for ever: a folded patch, whose flips are refused, would otherwise
    # split its obtuse edges without end), compiled: split_kernels.obtuse_edges
    h1, h2, worst = obtuse_edges(p, f, lv, float(limit))
    a, b = f[h1 // 3, h1 % 3], f[h1 // 3, (h1 % 3 + 1) % 3]
    c = f[h1 // 3, (h1 % 3 + 2) % 3]
    d = f[h2 // 3, (h2 % 3 + 2) % 3]
    cand = np.arange(len(h1))
    if stuck is not None and len(cand):
        cand = cand[~_encroached(p, stuck, (p[a[cand]] + p[b[cand]]) / 2, lens=lens)]
    empty = np.zeros((0, 3))
    if not len(cand):
        return f, lab, empty, np.zeros(0)
    cand = cand[np.argsort(-worst[cand], kind="stable")]
    f1, f2 = h1[cand] // 3, h2[cand] // 3
    taken = np.zeros(len(f), dtype=bool)
    keep = []
    for i in range(len(cand)):  # sequential: a greedy independent set, worst edge first (few edges)
        if not taken[f1[i]] and not taken[f2[i]]:
            taken[f1[i]] = taken[f2[i]] = True
            keep.append(i)
    sel = cand[keep]
    f1, f2 = h1[sel] // 3, h2[sel] // 3
    a, b, c, d = a[sel], b[sel], c[sel], d[sel]
    m = nv + np.arange(len(sel))
    out = f.copy()
    out[f1] = np.stack([a, m, c], 1)
    out[f2] = np.stack([b, m, d], 1)
    out = np.vstack([out, np.stack([m, b, c], 1), np.stack([m, a, d], 1)])
    lab = np.concatenate([lab, lab[f1], lab[f2]])
    return out, lab, (p[a] + p[b]) / 2, (lv[a] + lv[b]) / 2


@dataclass(frozen=True, eq=False)
class AngleRefined:
    """vertices: (V + K, 3), the input vertices then K inserted ones; faces: the patch faces;
    inserted: K; forced: (M,) whether a face's smallest angle lies between two edges that cannot
    change (``corner_fixed``), so no refinement can raise it; bad: (M,) faces still below the target
    that are not forced; rounds: insertion rounds run."""

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    inserted: int
    forced: NDArray[np.bool_]
    bad: NDArray[np.bool_]
    rounds: int


def corner_angles(p: NDArray[np.float64], f: NDArray[np.int64]) -> NDArray[np.float64]:
    """(M, 3) angle at each corner of each face, radians (column k: at f[:, k]): atan2(|u x w|, u . w)
    per corner, compiled (refine_kernels.corner_angles; tests/test_refine_kernels.py checks it against
    the numpy expression)."""
    return _corner_angles(p, f)


def refine_angles(vertices: NDArray[np.float64], patch: NDArray[np.int64], fixed_faces: NDArray[np.int64], *,
                  min_angle: float = 20.0, margin: float = 2.0, locked: NDArray[np.int64] | None = None,
                  movable: NDArray[np.int64] | None = None, max_rounds: int = 40, budget: float = 3.0,
                  rings: int = 3) -> AngleRefined:
    """Delaunay refinement of a patch for its angles: insert a point into every bad triangle until no
    triangle has an angle below ``min_angle`` degrees, or only forced ones are left.

    **(choice)**, beyond the spec's refinement (frep.md §4, :func:`refine`, which matches the density
    of the surroundings but bounds no angle): Chew's / Ruppert's Delaunay refinement with Üngör's
    off-centres (Üngör 2004, "Off-centers: a new type of Steiner points for computing size-optimal
    quality-guaranteed Delaunay triangulations"). A triangle (x, a, b) with its smallest angle at x
    (opposite the shortest edge ab) gets a new point on the perpendicular bisector of ab, in its
    plane, at the distance that makes (a, b, new) equilateral, or at the circumcentre if that is
    nearer (it is when the angle at x is above 30 degrees); the point lies in the triangle's
    circumcircle, so the Delaunay flips that follow (:func:`relax`) remove the triangle. Where that
    point falls outside the triangle (an obtuse corner at a or b) or too near another vertex, the
    triangle's longest splittable edge is halved instead (Rivara's bisection). The target is
    ``min_angle + margin`` so that the flips and the final positions keep the result above
    ``min_angle``.

    What cannot change: the hole border (edges shared with ``fixed_faces``) and ``locked`` edges
    (continued creases) are never split nor flipped. A triangle whose smallest angle lies between two
    such edges is **forced**: every triangulation of the patch has an angle at most that small at
    that corner (e.g. a hole border corner of 10 degrees), so it is left as it is. A triangle with a
    zero-length edge (two input vertices at one position, a split non-manifold vertex) is forced
    too (the copies stay apart in the output; merged, the face vanishes). New points lie in the
    plane of the triangle they split, so the patch's shape does not change (flips of non-planar
    quads aside); smoothing moves vertices in their tangent plane only. ``budget``: at most
    ``budget`` times the patch's faces are inserted (a safety bound; refinement around forced
    corners stops by the forced test).
    Once the insertions stop, :func:`_polish` tries local changes on each face still below the bound
    (a point, a halved edge, a graded fan at a border corner), keeping those that improve the angles
    and fold nothing.
    ``movable``: vertices (besides the inserted ones) that the smoothing may move (new vertices of
    the patch; a vertex of a ``fixed_faces`` face never moves, whatever ``movable`` says). ``rings``: how
    far around the bad faces the patch may change.
    """
    p = np.asarray(vertices, dtype=np.float64)
    f = np.array(patch, dtype=np.int64, copy=True).reshape(-1, 3)
    fixed = np.asarray(fixed_faces, dtype=np.int64).reshape(-1, 3)
    target = np.radians(min_angle + margin)
    lk = np.asarray(locked, dtype=np.int64).reshape(-1, 2) if locked is not None and len(locked) else None
    f, _ = relax(p, f, fixed, locked=lk)
    forced, bad, _ = _bad_triangles(p, f, fixed, lk, target)
    P, rest, inserted, rounds = p, np.zeros((0, 3), dtype=np.int64), 0, 0
    if bad.any():
        # only the faces within ``rings`` rings of the bad ones change: the rest of the patch is held
        # like the fixed faces (its edges next to the region do not flip), so a round costs what the
        # region costs, not what the whole patch does
        near = np.zeros(len(p), dtype=bool)
        near[f[bad]] = True
        for _ in range(rings):
            near[f[near[f].any(axis=1)]] = True
        region = near[f].any(axis=1)
        rest = f[~region]
        inside = np.zeros(len(p), dtype=bool)
        inside[f[region]] = True
        held = np.vstack([fixed, rest[inside[rest].any(axis=1)]])  # every other face at a region vertex
        free = np.zeros(len(p), dtype=bool)
        if movable is not None:
            free[np.asarray(movable, dtype=np.int64)] = True
        free[fixed.ravel()] = False  # a vertex of a fixed face never moves: that face would change
        P, sub, inserted, rounds = _refine_region(p, f[region], held, lk, free, target, np.radians(min_angle),
                                                  max_rounds, int(budget * max(len(f), 1)))
        if not _manifold(np.vstack([held, sub])) and _manifold(np.vstack([held, f[region]])):
            P, inserted, sub = p, 0, f[region]  # a safety net: a region that lost its manifold edges
        # the rest was not bad (its forced faces stay forced); only the region is measured again
        forced_sub, bad_sub, _ = _bad_triangles(P, sub, held, lk, np.radians(min_angle))
        forced_rest = forced[~region] & (corner_angles(p, rest).min(axis=1) < np.radians(min_angle))
        return AngleRefined(P, np.vstack([rest, sub]), inserted, np.concatenate([forced_rest, forced_sub]),
                            np.concatenate([np.zeros(len(rest), dtype=bool), bad_sub]), rounds)
    return AngleRefined(p, f, 0, forced & (corner_angles(p, f).min(axis=1) < np.radians(min_angle)), bad, 0)


def _manifold(faces: NDArray[np.int64]) -> bool:
    """No edge has more than two faces, and no directed edge appears twice."""
    he = halfedges(faces)
    return bool(edge_table(faces).counts.max(initial=0) <= 2 and len(np.unique(he, axis=0)) == len(he))


def _refine_region(p: NDArray[np.float64], f: NDArray[np.int64], fixed: NDArray[np.int64],
                   lk: NDArray[np.int64] | None, movable: NDArray[np.bool_], target: float, strict: float,
                   max_rounds: int, limit: int, cleanup: int = 4
                   ) -> tuple[NDArray[np.float64], NDArray[np.int64], int, int]:
    """The rounds of :func:`refine_angles` on one region: smooth, flip, insert, flip; then up to
    ``cleanup`` passes that may collapse or move the inserted points too. Returns (vertices, faces,
    points inserted, rounds)."""
    P = p.copy()
    nv0 = len(p)
    inserted = rounds = idle = 0
    while rounds < max_rounds:  # sequential: smooth, flip, insert, measure again
        rounds += 1
        f, _ = relax(P, f, fixed, locked=lk)
        _, bad, choice = _bad_triangles(P, f, fixed, lk, target)
        if not bad.any():
            break
        free = np.concatenate([movable, np.ones(len(P) - nv0, dtype=bool)])  # inserted points move too
        # moves only around faces below the bound itself (the margin is for the insertions)
        below = bad & (corner_angles(P, f).min(axis=1) < strict)
        moved = smooth_bad(P, f, free, np.flatnonzero(below)) if below.any() else 0
        if moved:
            f, _ = relax(P, f, fixed, locked=lk)
            _, bad, choice = _bad_triangles(P, f, fixed, lk, target)
            if not bad.any():
                break
        new_pts = np.zeros((0, 3))
        if inserted < limit:
            # no point into a face at a crumple (two faces folded over each other: a thin part's projections
            # crossed): points there multiply into clusters of tiny faces (bunny-islands' ear tip: 202 -> 1088
            # edges below 1/5 of the median, 174 points); the moves and collapses unfold it instead (166, 19)
            crumpled = np.zeros(len(P), dtype=bool)
            crumpled[f[_folded_pairs(P, f, ignore=lk).ravel()]] = True
            ins = np.flatnonzero(bad)
            new_pts, f = _insert(P, f, fixed, lk, ins[~crumpled[f[ins]].any(axis=1)], choice, len(P))
        removed = 0
        if not len(new_pts):  # Ruppert would split the border edge a free vertex encroaches: remove it
            # (not the points inserted here: inserting and removing one could alternate for ever)
            f, removed = _collapse_bad(P, f, fixed, lk, np.r_[movable, np.zeros(len(P) - nv0, dtype=bool)],
                                       np.flatnonzero(bad))
        idle = 0 if len(new_pts) or removed else idle + 1
        if not len(new_pts) and not moved and not removed or idle >= 2:  # two rounds of moves alone: settled
            break
        if len(new_pts):
            P = np.vstack([P, new_pts])
            inserted += len(new_pts)
    # once nothing is inserted any more, the points inserted here may go too: an off-centre that fixed one
    # face may have left a sliver on a long border edge that no later point could fix (featuretype: 148.9
    # deg at an inserted point 0.02 from a 0.41 border edge); removing it cannot start an insert-remove
    # cycle now, and _collapse_bad only collapses or moves a vertex when that raises its star's smallest angle
    everyone = np.r_[movable, np.ones(len(P) - nv0, dtype=bool)]
    for _ in range(cleanup):  # sequential: each pass's collapses change the next pass's bad faces
        f, _ = relax(P, f, fixed, locked=lk)
        _, bad, _ = _bad_triangles(P, f, fixed, lk, target)
        if not bad.any():
            break
        f, removed = _collapse_bad(P, f, fixed, lk, everyone, np.flatnonzero(bad), below=strict)
        if not removed:
            break
    f, _ = relax(P, f, fixed, locked=lk)
    P, f, added = _polish(P, f, fixed, lk, np.r_[movable, np.ones(len(P) - nv0, dtype=bool)], strict)
    return P, f, inserted + added, rounds


def _score(p: NDArray[np.float64], f: NDArray[np.int64], fixed: NDArray[np.int64], lk: NDArray[np.int64] | None,
           strict: float, hard: float) -> tuple[int, int, float]:
    """(faces below ``hard``, faces below ``strict``, minus the smallest angle), all over the faces that
    are not forced: smaller is better, compared in that order."""
    forced, bad, _ = _bad_triangles(p, f, fixed, lk, strict)
    a = corner_angles(p, f[~forced]).min(axis=1)
    return int((a < hard).sum()), int(bad.sum()), -float(a.min()) if len(a) else -np.pi


def _pareto(sc: tuple[int, int, float], best: tuple[int, int, float]) -> bool:
    """Whether the score ``sc`` (:func:`_score`) improves on ``best``: no more faces below the bound, no
    smaller angle, one of them strictly (the faces below the hard bound may change among themselves)."""
    return (sc[1], sc[2]) != (best[1], best[2]) and sc[1] <= best[1] and sc[2] <= best[2]


def _better(sc: tuple[int, int, float], best: tuple[int, int, float]) -> bool:
    """Whether the score ``sc`` (:func:`_score`) improves on ``best``: the smallest angle does not go
    down, and either fewer faces are below the hard bound, or as many and no more below the bound,
    and something changed. So a trial never trades the smallest angle for the count, and the count
    below the bound may grow only to lift faces above the hard bound (the fans at a border corner
    where every triangulation has a face below the bound: four faces at 17.5 deg instead of two at 13.5)."""
    return sc[2] <= best[2] and sc != best and (sc[0] < best[0] or sc[0] == best[0] and sc[1] <= best[1])


def _split_edge(f: NDArray[np.int64], i: int, e: int, m: int) -> NDArray[np.int64] | None:
    """The faces with edge e of face i (f[i, e] -> f[i, e + 1]) halved at the new vertex m: both faces
    of the edge split in two, orientation kept; None if the edge has no second face."""
    a, b, c = f[i, e], f[i, (e + 1) % 3], f[i, (e + 2) % 3]
    js = np.flatnonzero(((f == b) & (np.roll(f, -1, axis=1) == a)).any(axis=1))
    if len(js) != 1:
        return None
    j = int(js[0])
    d = int(f[j][(f[j] != a) & (f[j] != b)][0])
    g = f.copy()
    g[i] = (a, m, c)
    g[j] = (b, m, d)
    return np.vstack([g, [[m, b, c], [m, a, d]]])


def _folded_pairs(p: NDArray[np.float64], f: NDArray[np.int64], *, cos: float = -0.25,
                  ignore: NDArray[np.int64] | None = None) -> NDArray[np.int64]:
    """(K, 2) the two faces of each edge of ``f`` (topology.face_adjacency) whose faces turn more than
    acos(``cos``) against each other (105 deg: a face folded over its neighbour, not a surface bent
    smoothly; a CAD part's own sharp edges count too, except the edges ``ignore`` (E, 2), e.g. the
    continued creases)."""
    t = p[f]
    n = _cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    pairs, shared = face_adjacency(f, manifold_only=False, with_edges=True)
    folded = np.einsum("ij,ij->i", n[pairs[:, 0]], n[pairs[:, 1]]) < cos
    pairs, shared = pairs[folded], shared[folded]
    if ignore is not None and len(ignore) and len(pairs):
        ig = np.sort(np.asarray(ignore, dtype=np.int64).reshape(-1, 2), axis=1)
        nv = len(p)
        pairs = pairs[~np.isin(shared[:, 0] * nv + shared[:, 1], ig[:, 0] * nv + ig[:, 1])]
    return pairs


def _split_face(f: NDArray[np.int64], i: int, m: int) -> NDArray[np.int64]:
    """The faces with face i split in three at the new vertex m (face i keeps its place, the other two
    go last), orientation kept."""
    a, b, c = f[i]
    g = np.vstack([f, [[b, c, m], [c, a, m]]])
    g[i] = (a, b, m)
    return g


def _graded_points(p: NDArray[np.float64], f: NDArray[np.int64], keep: NDArray[np.bool_], v: int, k: int
                   ) -> NDArray[np.float64] | None:
    """``k`` points for a graded fan at vertex ``v``: on rays from v that split the angle of its open
    fan of faces (those not in ``keep``) evenly, at radii growing geometrically from the first spoke's
    length to the last one's, so that each face of the new fan at v has spokes of a bounded ratio (in
    a triangle with angle alpha at v and angles >= beta at its other corners, the ratio of the two
    spokes is at most sin(180 - alpha - beta) / sin(beta): a 0.04 chord and a 0.41 border edge 60 deg
    apart need four faces for 15 deg). None where the faces at v are not one open fan."""
    rows = np.flatnonzero((f == v).any(axis=1) & ~keep)
    if not len(rows):
        return None
    star = f[rows]
    rot = np.argmax(star == v, axis=1)
    a = star[np.arange(len(star)), (rot + 1) % 3]
    b = star[np.arange(len(star)), (rot + 2) % 3]
    first = np.setdiff1d(a, b)
    if len(first) != 1 or len(np.unique(a)) != len(a):
        return None
    nxt = dict(zip(a.tolist(), b.tolist()))
    link = [int(first[0])]
    while link[-1] in nxt and len(link) <= len(a):
        link.append(nxt[link[-1]])
    if len(link) != len(a) + 1:
        return None
    nrm = face_cross(p, star).sum(axis=0)
    if np.linalg.norm(nrm) == 0:
        return None
    nrm /= np.linalg.norm(nrm)
    d0 = p[link[0]] - p[v]
    r0, r1 = float(np.linalg.norm(d0)), float(np.linalg.norm(p[link[-1]] - p[v]))
    e1 = d0 - (d0 @ nrm) * nrm
    e1 /= max(float(np.linalg.norm(e1)), 1e-300)
    e2 = np.cross(nrm, e1)  # towards the fan's other end (the faces wind counter-clockwise about nrm)
    theta = corner_angles(p, np.c_[np.full(len(a), v), a, b])[:, 0].sum()
    j = np.arange(1, k + 1)[:, None] / (k + 1)
    return p[v] + r0 * (r1 / max(r0, 1e-300)) ** j * (np.cos(theta * j) * e1 + np.sin(theta * j) * e2)


def _insert_points(p: NDArray[np.float64], f: NDArray[np.int64], x: NDArray[np.float64]
                   ) -> tuple[NDArray[np.float64], NDArray[np.int64]] | None:
    """Insert the points x one by one into the face they project into (the nearest such face's plane,
    where the point is put), each splitting it in three. None if a point lies in no face."""
    for y in x:  # sequential: each split changes the faces the next one may lie in
        inside = _inside(p, f, np.broadcast_to(y, (len(f), 3)), margin=0.0)
        if not inside.any():
            return None
        cand = np.flatnonzero(inside)
        t = p[f[cand]]
        n = face_normals(p, f[cand])
        d = np.einsum("ij,ij->i", y - t[:, 0], n)
        h = int(np.argmin(np.abs(d)))
        f = _split_face(f, int(cand[h]), len(p))
        p = np.vstack([p, y - d[h] * n[h]])
    return p, f


def _run_trials(trials: list, p: NDArray[np.float64], m: int, ring: NDArray[np.int64], held: NDArray[np.int64],
                lk: NDArray[np.int64] | None, strict: float, hard: float, near: float, sweeps: int,
                folds: int) -> list:
    """:func:`_polish`'s trials (vertices, faces, free flags, points added), each flipped and smoothed
    (moves on an 11 x 11 grid: a trial is one of many), as (score, vertices, faces, free, points added)
    for those that stay a manifold and fold no more faces than ``folds``."""
    out = []
    for q, g, fr, n_new in trials:  # independent trials (a handful)
        verts = np.r_[np.arange(m, len(q)), ring]
        verts = verts[fr[verts]]
        for s in range(2 * sweeps):
            if s % 2 == 0:
                g, _ = relax(q, g, held, locked=lk)
            for c in verts:  # sequential: each move changes its neighbours' stars
                rows = np.flatnonzero((g == c).any(axis=1))
                before = corner_angles(q, g[rows]).min()
                if before < strict + near:  # a star well above the bound: left as it is (time)
                    _move_best(q, g[rows], int(c), before, grid=11)
        g, _ = relax(q, g, held, locked=lk)
        if _manifold(np.vstack([held, g])) and len(_folded_pairs(q, np.vstack([held, g]))) <= folds:
            out.append((_score(q, g, held, lk, strict, hard), q, g, fr, n_new))
    return out


def _pick(done: list, best: tuple[int, int, float], better) -> tuple | None:
    """The trial of ``done`` (:func:`_run_trials`) with the smallest score among those ``better`` than
    ``best``, or None."""
    ok = [t for t in done if better(t[0], best)]
    return min(ok, key=lambda t: t[0]) if ok else None


def _polish(p: NDArray[np.float64], f: NDArray[np.int64], fixed: NDArray[np.int64], lk: NDArray[np.int64] | None,
            free: NDArray[np.bool_], strict: float, *, rounds: int = 3, tries: int = 30, sweeps: int = 2,
            near: float = np.radians(5.0), hard: float | None = None
            ) -> tuple[NDArray[np.float64], NDArray[np.int64], int]:
    """The faces the refinement left below ``strict`` (radians) and not forced, worst first: each tries
    (a) moving the free vertices around it, (b) a new point at its centroid, (c) each of its edges that
    may split halved; every trial is followed by flips (:func:`relax`) and ``sweeps`` rounds of two
    :func:`_move_best` passes over the new point and the free vertices of the faces at the face's
    corners whose stars have an angle within ``near`` (radians) of ``strict``. The trials change only
    the faces at those vertices (the rest is held like the border, as :func:`refine_angles` holds the
    faces outside its region), and the best one is kept when it improves them (:func:`_pareto`: no
    more faces below ``strict`` and no smaller angle, over the faces that are not forced, one of them
    strictly, so the whole patch improves too) and folds no more faces over their neighbours
    (:func:`_folded_pairs`). Where none does, graded fans at the face's pinned corners (:func:`_graded_points`,
    1-4 points) are tried the same way; where none of those does either and the face is below ``hard``
    (default 3/4 of ``strict``: 15 deg for 20), any trial that lifts faces above ``hard`` without
    lowering the smallest angle (:func:`_better`).

    A local search, not a Delaunay refinement: where the border forbids every point the off-centre rule
    would insert (a 0.41 border edge beside a fan of 0.04 chords, featuretype: 13.2 deg), points in
    the face or on rays from the corner, plus moves of their neighbours, still find a fan that grades
    from the short edges to the long one. ``tries`` bounds the faces tried, over all ``rounds`` (a
    rounded cube of input slivers: 30 faces cost 3 s; without a bound, 8 s more for 19 faces fewer
    below the bound). Returns (vertices, faces, points added).
    """
    hard = 0.75 * strict if hard is None else hard
    added = tried = 0
    for _ in range(rounds):  # sequential: each kept trial changes the next face's surroundings
        _, bad, _ = _bad_triangles(p, f, fixed, lk, strict)
        if not bad.any():
            break
        ang = corner_angles(p, f).min(axis=1)
        order = np.flatnonzero(bad)[np.argsort(ang[bad], kind="stable")]
        kept = False
        if tried >= tries:
            break
        for tri in f[order].copy():  # sequential: trials on the current mesh
            hit = np.flatnonzero((f == tri).all(axis=1))
            if not len(hit):
                continue  # a kept trial of an earlier face changed this one
            ring = np.unique(f[np.isin(f, tri).any(axis=1)])
            loc = np.isin(f, ring).any(axis=1)  # every face at a vertex that may move
            sub, rest = f[loc], f[~loc]
            at = np.unique(sub)
            held = np.vstack([fixed[np.isin(fixed, at).any(axis=1)], rest[np.isin(rest, at).any(axis=1)]])
            i = int(np.flatnonzero((sub == tri).all(axis=1))[0])
            best = _score(p, sub, held, lk, strict, hard)
            folds = len(_folded_pairs(p, np.vstack([held, sub])))  # no trial may fold more faces over their neighbours
            stuck = unchangeable(sub, len(p), held, lk)
            m = len(p)
            trials = [(p.copy(), sub.copy(), free, 0),
                      (np.vstack([p, p[tri].mean(axis=0)]), _split_face(sub, i, m), np.r_[free, True], 1)]
            for e in range(3):
                g = None if stuck[i, e] else _split_edge(sub, i, e, m)
                if g is not None:
                    trials.append((np.vstack([p, (p[tri[e]] + p[tri[(e + 1) % 3]]) / 2]), g, np.r_[free, True], 1))
            fans = [(v, k) for v in tri[~free[tri]] for k in (1, 2, 3, 4)]  # graded fans at its pinned corners

            def fan(v: int, k: int, forced: NDArray[np.bool_]) -> tuple | None:
                x = _graded_points(p, sub, forced, int(v), k)
                got = None if x is None else _insert_points(p, sub, x)
                return None if got is None else (got[0], got[1], np.r_[free, np.ones(k, dtype=bool)], k)

            # the simple trials first, then the fans (dearer: several points each), each kept only if it
            # improves both counts (_pareto); then either, if it lifts faces above the hard bound (_better)
            args = (p, m, ring, held, lk, strict, hard, near, sweeps, folds)
            done = _run_trials(trials, *args)
            chosen = _pick(done, best, _pareto)
            if chosen is None:
                forced = _bad_triangles(p, sub, held, lk, strict)[0]  # the fans keep the forced faces
                fans = _run_trials([t for t in (fan(v, k, forced) for v, k in fans) if t is not None], *args)
                chosen = _pick(fans, best, _pareto) or _pick(done + fans, best, _better)
            if chosen is not None:
                _, p, g, free, n_new = chosen
                f = np.vstack([rest, g])
                added += n_new
                kept = True
            tried += 1
            if tried >= tries:
                break
        if not kept:
            break
    return p, f, added


def _inside(p: NDArray[np.float64], tri: NDArray[np.int64], q: NDArray[np.float64], *,
            margin: float = 0.02) -> NDArray[np.bool_]:
    """(K,) whether q[i] projected into the plane of triangle tri[i] lies inside it, every
    barycentric coordinate above ``margin``."""
    x, a, b = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    e0, e1, w = a - x, b - x, q - x
    d00, d01, d11 = (e0 * e0).sum(1), (e0 * e1).sum(1), (e1 * e1).sum(1)
    d20, d21 = (w * e0).sum(1), (w * e1).sum(1)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-300)
    s = (d11 * d20 - d01 * d21) / den
    t = (d00 * d21 - d01 * d20) / den
    return (s > margin) & (t > margin) & (1 - s - t > margin)


def _encroached(p: NDArray[np.float64], seg: NDArray[np.int64], x: NDArray[np.float64], *,
                lens: float = 120.0) -> NDArray[np.bool_]:
    """(K,) whether each point x[i] lies in the diametral lens of one of the segments ``seg``
    (S, 2): it sees the segment at an angle above ``lens`` degrees (Shewchuk's lens, 120: a
    triangle of the segment and x[i] would have an angle below 30 degrees at its other corners).
    A point in a lens lies in the segment's diametral ball, so each segment tests only the points
    in its ball (a KD-tree of the points; a long border edge among short ones is found however far
    its midpoint lies: the 8 nearest midpoints used before missed it)."""
    from scipy.spatial import cKDTree

    x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
    out = np.zeros(len(x), dtype=bool)
    if not len(seg) or not len(x):
        return out
    a, b = p[seg[:, 0]], p[seg[:, 1]]
    hits = cKDTree(x).query_ball_point((a + b) / 2, np.linalg.norm(a - b, axis=1) / 2)
    ns = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(seg))
    if not ns.sum():
        return out
    si = np.repeat(np.arange(len(seg)), ns)
    xi = np.concatenate([np.asarray(h, dtype=np.int64) for h in hits if len(h)])
    u = a[si] - x[xi]
    w = b[si] - x[xi]
    ang = np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))
    out[xi[ang > np.radians(lens)]] = True
    return out


def _bad_triangles(p: NDArray[np.float64], f: NDArray[np.int64], fixed: NDArray[np.int64],
                   locked: NDArray[np.int64] | None, target: float
                   ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.int64]]:
    """(forced, bad, corner of the smallest angle) per face; bad = below ``target`` and not forced."""
    if not len(f):
        z = np.zeros(0, dtype=bool)
        return z, z, np.zeros(0, dtype=np.int64)
    ang = corner_angles(p, f)
    k = np.argmin(ang, axis=1)
    small = ang[np.arange(len(f)), k] < target
    stuck = unchangeable(f, len(p), fixed, locked)
    r = np.arange(len(f))
    # edges at corner k: edge k (f[k] -> f[k+1]) and edge k-1 (f[k-1] -> f[k])
    corner_fixed = stuck[r, k] & stuck[r, (k + 2) % 3]
    ln = np.linalg.norm(p[f] - p[np.roll(f, -1, axis=1)], axis=2)
    glued = (ln <= 1e-12 * max(1.0, float(ln.max()))).any(axis=1)  # two copies of a split non-manifold vertex
    forced = small & (corner_fixed | glued)
    return forced, small & ~forced, k


def _insert(p: NDArray[np.float64], f: NDArray[np.int64], fixed: NDArray[np.int64], locked: NDArray[np.int64] | None,
            bad: NDArray[np.int64], corner: NDArray[np.int64], nv: int
            ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """One round of insertions into the bad faces (worst first, each face used once): off-centre
    points split their face in three; the fallback halves an edge (both its faces). Returns (new
    points, faces)."""
    from scipy.spatial import cKDTree

    ang = corner_angles(p, f[bad]).min(axis=1)
    bad = bad[np.argsort(ang, kind="stable")]
    k = corner[bad]
    r = np.arange(len(bad))
    x = f[bad, k]
    a = f[bad, (k + 1) % 3]
    b = f[bad, (k + 2) % 3]
    ab = p[b] - p[a]
    lab = np.linalg.norm(ab, axis=1)
    mid = (p[a] + p[b]) / 2
    toward = p[x] - mid
    ue = ab / np.maximum(lab, 1e-300)[:, None]
    u = toward - np.einsum("ij,ij->i", toward, ue)[:, None] * ue
    un = np.linalg.norm(u, axis=1)
    u /= np.maximum(un, 1e-300)[:, None]
    theta = corner_angles(p, f[bad])[r, k]
    # (a, b, q) equilateral, or the circumcentre (distance |ab| / (2 tan theta) from mid) if nearer
    d = np.minimum(np.sqrt(3) / 2 * lab, lab / (2 * np.tan(np.maximum(theta, 1e-12))))
    q = mid + d[:, None] * u
    inside = _inside(p, np.stack([x, a, b], 1), q) & (un > 0)
    used = np.unique(f)
    near, _ = cKDTree(p[used]).query(q)
    ok_pt = near > 0.5 * lab  # inside the face, or (below) in a neighbour across an edge at x
    # Ruppert's encroachment rule for the edges that cannot split, with Shewchuk's diametral lens: a
    # point that sees a border / locked edge at more than 120 degrees is not inserted (it would make
    # a flat triangle on that edge)
    stuck = unchangeable(f, len(p), fixed, locked)
    se = np.stack([f[stuck], np.roll(f, -1, axis=1)[stuck]], axis=1)

    def encroaches(x: NDArray[np.float64]) -> NDArray[np.bool_]:
        return _encroached(p, se, x)

    ok_pt &= ~encroaches(q)
    # the fallback: the longest edge of the face that may split (not a border / locked / single edge);
    # its midpoint's encroachment does not change during the round (the stuck edges do not), so it
    # is tested for every bad face at once
    tri = p[f[bad]]
    el_all = np.linalg.norm(tri[:, [1, 2, 0]] - tri, axis=2)
    el_all[stuck[bad]] = -1
    e_all = np.argmax(el_all, axis=1)
    ea_all = f[bad, e_all]
    eb_all = f[bad, (e_all + 1) % 3]
    mp_all = (p[ea_all] + p[eb_all]) / 2
    mp_enc = encroaches(mp_all)
    he = halfedges(f)
    hkey = he[:, 0] * len(p) + he[:, 1]
    order = np.argsort(hkey)
    taken = np.zeros(len(f), dtype=bool)
    faces = [f]
    grow: list[NDArray[np.int64]] = []
    # the points inserted this round (vertices nv, nv + 1, ...) and their clearance radii (at most one
    # per bad face)
    acc, acc_r, n_acc = np.empty((len(bad), 3)), np.empty(len(bad)), 0

    def clear_of_accepted(x: NDArray[np.float64]) -> bool:
        return bool(np.all(np.sqrt(((acc[:n_acc] - x) ** 2).sum(axis=1)) > acc_r[:n_acc]))
    for i in range(len(bad)):  # sequential: a greedy independent set, worst face first (tens of faces)
        fi = int(bad[i])
        if taken[fi]:
            continue
        host = -1
        if ok_pt[i] and clear_of_accepted(q[i]):
            if inside[i]:
                host = fi
            else:  # an obtuse corner at a or b: the point lies across the edge (x, a) or (b, x)
                for e in (int(k[i]), (int(k[i]) + 2) % 3):
                    if stuck[fi, e]:
                        continue
                    ea, eb = f[fi, e], f[fi, (e + 1) % 3]
                    g = int(order[np.searchsorted(hkey[order], eb * len(p) + ea)] // 3)
                    if not taken[g] and _inside(p, f[g][None], q[i][None])[0]:
                        host = g
                        break
        if host >= 0:
            taken[fi] = taken[host] = True
            m = nv + n_acc
            th = p[f[host]]
            nh = np.cross(th[1] - th[0], th[2] - th[0])
            nh /= max(float(np.linalg.norm(nh)), 1e-300)
            q[i] -= ((q[i] - th[0]) @ nh) * nh  # in the plane of the face it splits
            acc[n_acc], acc_r[n_acc] = q[i], 0.5 * float(lab[i])
            n_acc += 1
            i0, i1, i2 = f[host]
            f[host] = (i0, i1, m)
            grow.append(np.array([[i1, i2, m], [i2, i0, m]]))
            continue
        e = int(e_all[i])
        el = el_all[i]
        if el[e] <= 0:
            continue
        ea, eb = int(ea_all[i]), int(eb_all[i])
        j = order[np.searchsorted(hkey[order], eb * len(p) + ea)]
        g = int(j // 3)
        mp = mp_all[i]
        if taken[g] or mp_enc[i] or not clear_of_accepted(mp):
            continue
        taken[fi] = taken[g] = True
        m = nv + n_acc
        acc[n_acc], acc_r[n_acc] = mp, 0.25 * float(el[e])
        n_acc += 1
        c = f[fi, (e + 2) % 3]
        dd = f[g, (j % 3 + 2) % 3]
        f[fi] = (ea, m, c)
        f[g] = (eb, m, dd)
        grow.append(np.array([[m, eb, c], [m, ea, dd]]))
    if not n_acc:
        return np.zeros((0, 3)), f
    return acc[:n_acc].copy(), np.vstack(faces + grow)


FLAT = np.radians(1.0)  # a face with an angle below this has (almost) no area


def no_area(p: NDArray[np.float64], f: NDArray[np.int64]) -> NDArray[np.bool_]:
    """(M,) whether each face of ``f`` has (almost) no area: an angle below ``FLAT`` (three corners
    on one line: a cap over an edge, or a needle at a vertex)."""
    return corner_angles(p, f).min(axis=1) < FLAT if len(f) else np.zeros(0, dtype=bool)


def _collapse_bad(p: NDArray[np.float64], f: NDArray[np.int64], fixed: NDArray[np.int64],
                  locked: NDArray[np.int64] | None, free: NDArray[np.bool_], bad: NDArray[np.int64],
                  below: float | None = None, move: NDArray[np.bool_] | None = None) -> tuple[NDArray[np.int64], int]:
    """Remove free vertices of the bad faces by collapsing each onto the neighbour that leaves the
    best smallest angle, when that raises the smallest angle of its faces: the vertex a Delaunay
    refinement could not fix (no point was inserted this round, and moving it did not help): first
    the vertices inside the diametral lens of a border edge, which may not split, so no point can be
    inserted near them, then the others (e.g. a new vertex a fraction of an edge from a border
    vertex, whose off-centres all encroach the border). A collapse keeps
    the surface a manifold (the link condition: the two ends share only the two vertices opposite
    their edge), folds no face and never touches a vertex on a border, locked or single edge.
    ``below`` (radians): a collapse must also leave no more faces with an angle below it than the star
    had (a star holding a forced corner has that corner's angle as its smallest whatever the collapse
    does, so the smallest angle alone would accept any collapse that does not go below it).
    ``move``: the vertices that may be moved where no collapse helps (default: every ``free`` one).
    Returns (faces, collapses); the removed vertex stays in ``p``, unreferenced."""
    stuck = unchangeable(f, len(p), fixed, locked)
    nv = len(p)
    a, b = f[stuck], np.roll(f, -1, axis=1)[stuck]
    on_stuck = np.zeros(nv, dtype=bool)
    on_stuck[a] = True
    on_stuck[b] = True
    cand = np.unique(f[bad])
    cand = cand[free[cand] & ~on_stuck[cand]]
    if len(cand):  # the vertices in the diametral lens of a border / locked edge first
        cand = cand[np.argsort(~_encroached(p, np.stack([a, b], axis=1), p[cand]), kind="stable")]
    done = 0
    fixed_of = VertexFaces(fixed, nv)
    face_of = VertexFaces(f, nv)  # rebuilt after each collapse (a move leaves the faces as they are)
    for c in cand:  # sequential: each collapse changes the stars of the next candidates
        rows = face_of.rows(int(c))
        if not len(rows):
            continue
        star = f[rows]
        t = p[star]
        n_old = _cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        star_ang = corner_angles(p, star).min(axis=1)
        before = star_ang.min()
        n_below = int((star_ang < below).sum()) if below is not None else 0
        # a face of no area (no_area) has no side to fold to: judged against the star's normal instead
        flat = star_ang < FLAT
        n_old[flat] = n_old.sum(axis=0)
        n_flat = int(flat.sum())
        ring = set(np.unique(star).tolist()) - {int(c)}
        best = None
        for u in ring:
            both = (star == u).any(axis=1)
            if both.sum() != 2:
                continue
            opp = set(np.unique(star[both]).tolist()) - {int(c), u}
            nu = set(np.unique(f[face_of.rows(u)]).tolist())
            nu |= set(np.unique(fixed[fixed_of.rows(u)]).tolist())  # and among the fixed faces
            nu -= {u}
            if nu & ring != opp:
                continue  # the link condition
            if both.all():
                continue  # a star of two faces (a pillow: c has no edge to collapse along)
            nf = star[~both].copy()
            nf[nf == c] = u
            t2 = p[nf]
            n_new = _cross(t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0])
            new_ang = corner_angles(p, nf).min(axis=1)
            ref = n_old[~both]
            judged = new_ang >= FLAT if n_flat else np.ones(len(nf), dtype=bool)  # no area: no side
            if (np.einsum("ij,ij->i", n_new[judged], ref[judged]) <= 0).any():
                continue  # a fold
            m = new_ang.min()
            if below is not None and (new_ang < below).sum() > n_below:
                continue
            # better: a larger smallest angle, or as large and fewer faces of no area (collinear
            # corners pressed onto one line: no single collapse lifts every one of them)
            fewer = n_flat > 0 and m >= before and int((new_ang < FLAT).sum()) < n_flat
            if (m > before or fewer) and (best is None or m > best[0]):
                best = (m, both, nf)
        if best is None:
            # no collapse keeps the link condition and helps (e.g. c and its nearest neighbour
            # share a third one): move c to where its star's smallest angle is largest
            if (move is None or move[c]) and _move_best(p, star, int(c), before):
                done += 1
            continue
        _, both, nf = best
        f = f.copy()
        f[rows[~both]] = nf
        f = np.delete(f, rows[both], axis=0)
        face_of = VertexFaces(f, nv)
        done += 1
    return f, done


def _cross(u: NDArray[np.float64], w: NDArray[np.float64]) -> NDArray[np.float64]:
    """u x w over the last axis (3), without np.cross's axis handling."""
    return np.stack([u[..., 1] * w[..., 2] - u[..., 2] * w[..., 1], u[..., 2] * w[..., 0] - u[..., 0] * w[..., 2],
                     u[..., 0] * w[..., 1] - u[..., 1] * w[..., 0]], axis=-1)


def _move_best(p: NDArray[np.float64], star: NDArray[np.int64], c: int, before: float, *, grid: int = 21,
               levels: int = 4, gain: float = np.radians(0.1)) -> bool:
    """Move vertex ``c`` (in place) to the point of its star's tangent plane where the smallest angle
    of its faces is largest, when that beats ``before`` by ``gain`` (radians) and folds no face: a
    grid search over the disc its ring spans (``grid`` x ``grid`` points), refined ``levels`` times
    around the best point. The umbrella and equilateral-apex steps of refine_kernels.smooth_bad look in
    two directions only; a vertex squeezed against a border vertex may need to move across its star
    (bunny scan: 9.8 -> 40 degrees where no collapse kept the surface a manifold). The tangent plane is
    the one of the star's normals' sum (its ring's vector area), unless a face's normal is against it:
    in a star folded over itself (at the copies of a pinched vertex) the normals cancel and their sum
    may lie along the surface, so the least-squares plane of the ring's points is used (torus:2:0 of
    bench/sweep.py, full mode: the output's farthest vertex from the torus 2.4 -> 0.4 % of the diagonal)."""
    t = p[star]
    n_old = _cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])  # (np.cross costs more than the search on a small star)
    nrm = n_old.sum(axis=0)
    nn = float(np.sqrt(nrm @ nrm))
    if nn == 0:
        return False
    nrm /= nn
    ring = p[np.unique(star[star != c])]
    _, sv, vt = np.linalg.svd(ring - ring.mean(axis=0))
    if sv[1] < RING_LINE * sv[0]:
        return False  # the ring lies along a line (slivers along a border or a crease): no tangent plane
    if (n_old @ nrm <= 0).any():  # folded: the plane the ring's points span
        nrm = vt[-1]
    e1 = _cross(nrm, np.eye(3)[int(np.argmin(np.abs(nrm)))])
    e1 /= np.sqrt(e1 @ e1)
    e2 = _cross(nrm, e1)
    at = star == c
    half = float(np.sqrt(((t - p[c]) ** 2).sum(axis=2).max()))  # the farthest ring vertex
    x = grid_search(t, at, p[c], half, e1, e2, n_old, before + gain, grid, levels)
    if np.isnan(x[0]):
        return False  # nothing better
    old, p[c] = p[c].copy(), _nearest_on(t, x) if ON_STAR else x
    if not ON_STAR:
        return True
    q = p[star]  # on the star's old faces: better there too, and folding nothing
    n_new = _cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0])
    if (np.einsum("ij,ij->i", n_new, n_old) <= 0).any() or corner_angles(p, star).min() < before + gain:
        p[c] = old
        return False
    return True


def _nearest_on(t: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """The point of the triangles ``t`` (S, 3, 3) nearest to point x (3,): trimesh's closest point on
    each triangle, the nearest of those."""
    from trimesh.triangles import closest_point

    cp = closest_point(t, np.broadcast_to(x, (len(t), 3)))
    return cp[int(np.argmin(((cp - x) ** 2).sum(axis=1)))]

"""Stage I: a discrete model of the border in parameter space (spec/hybrid.md §2).

The background grid covers P; every cell is classified by the signs of W at its four corners
(16 configurations, :func:`configuration`): A no crossing, B one corner cut off, C two adjacent
corners separated, D two opposite corners (ambiguous: the cell is split into four and classified
again). Crossings are found by root finding on W along the cell sides (``HybridModel.bisect``),
so border vertices lie on F = 0 to machine precision. Short edges (3D length < δ) are merged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .model import HybridModel

# Segment kinds: CURVE lies on F = 0; the sides of P are 0: u = a, 1: u = b, 2: v = c, 3: v = d.
CURVE = -1
SIDE_UA, SIDE_UB, SIDE_VC, SIDE_VD = 0, 1, 2, 3

# Corner order in a cell: 0 (u0, v0), 1 (u1, v0), 2 (u1, v1), 3 (u0, v1); cell sides k: corner k → k+1.
CLASS_A, CLASS_B, CLASS_C, CLASS_D = "A", "B", "C", "D"


def configuration(inside: NDArray[np.bool_]) -> NDArray[np.int64]:
    """(..., 4) corner signs (W >= 0) → configuration index 0..15 (bit k = corner k inside)."""
    b = np.asarray(inside, dtype=np.int64)
    return b[..., 0] | (b[..., 1] << 1) | (b[..., 2] << 2) | (b[..., 3] << 3)


def classify(config: int) -> str:
    """The class of one of the 16 configurations: A (0, 15), B (one corner differs),
    C (two adjacent corners differ), D (two opposite corners: 5, 10)."""
    n = bin(config).count("1")
    if n in (0, 4):
        return CLASS_A
    if n in (1, 3):
        return CLASS_B
    return CLASS_D if config in (5, 10) else CLASS_C


def cell_segments(config: int, centre_inside: bool = False) -> list[tuple[int, int]]:
    """The border segments inside a cell as pairs of cell sides (side k joins corner k and k+1).

    Each segment is oriented with the kept region on its left (counter-clockwise around it).
    For D cells the centre sign (asymptotic decider at the last split level) decides whether the
    inside corners are joined.
    """
    ins = [(config >> k) & 1 for k in range(4)]
    cls = classify(config)
    if cls == CLASS_A:
        return []
    crossed = [k for k in range(4) if ins[k] != ins[(k + 1) % 4]]
    if cls in (CLASS_B, CLASS_C):
        s0, s1 = crossed
        return [_orient(ins, s0, s1)]
    # D: the centre sign decides which pair of opposite corners is cut off (asymptotic decider)
    cut = [k for k in range(4) if ins[k] == (0 if centre_inside else 1)]
    return [_orient(ins, (k + 3) % 4, k) for k in cut]


def _orient(ins: list[int], s0: int, s1: int) -> tuple[int, int]:
    # Side s runs from corner s to corner s+1 (counter-clockwise). The segment starts on the crossed
    # side whose first corner is inside: then the kept corners are on its left.
    return (s0, s1) if ins[s0] == 1 else (s1, s0)


@dataclass(frozen=True)
class Border:
    """Stage I output. points (N, 2) in (u, v); segments (S, 2) vertex pairs with the kept region on
    the left; kinds (S,) CURVE or a side of P; polylines: chains of vertex indices (for display);
    grid: the (u, v) coordinates of the background grid lines; delta: the merge length per segment."""

    points: NDArray[np.float64]
    segments: NDArray[np.int64]
    kinds: NDArray[np.int64]
    polylines: list[NDArray[np.int64]]
    grid_u: NDArray[np.float64]
    grid_v: NDArray[np.float64]
    ambiguous_cells: int
    merged: int
    open_ends: int


def grid_lines(model: HybridModel, cells: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Grid lines with cells about square in 3D: `cells` along the longer direction."""
    a, b, c, d = model.surface.domain
    s = np.linspace(0, 1, 9)
    uu, vv = np.meshgrid(a + (b - a) * s, c + (d - c) * s, indexing="ij")
    p = model.surface(uu, vv)
    lu = np.linalg.norm(np.diff(p, axis=0), axis=-1).sum(0).mean()  # 3D length of the u-lines
    lv = np.linalg.norm(np.diff(p, axis=1), axis=-1).sum(1).mean()
    longest = max(lu, lv, 1e-300)
    nu = max(2, int(round(cells * lu / longest)))
    nv = max(2, int(round(cells * lv / longest)))
    return np.linspace(a, b, nu + 1), np.linspace(c, d, nv + 1)


def build_border(model: HybridModel, *, cells: int = 40, delta: float = 0.4, max_split: int = 4) -> Border:
    """Stage I (§2 steps 1-3): grid, 16 configurations, split ambiguous cells, root finding, merge."""
    if cells < 2:
        raise ValueError(f"cells: need at least 2, got {cells}")
    if not 0 <= delta < 1:
        raise ValueError(f"delta: the merge fraction of the cell diagonal must be in [0, 1), got {delta}")
    surf = model.surface
    gu, gv = grid_lines(model, cells)
    U, V = np.meshgrid(gu, gv, indexing="ij")
    Wg = model.W(U, V)
    if surf.periodic_u:
        Wg[-1, :] = Wg[0, :]
    if surf.periodic_v:
        Wg[:, -1] = Wg[:, 0]
    inside = Wg >= 0
    P3 = surf(U, V)
    diag3 = np.linalg.norm(P3[1:, 1:] - P3[:-1, :-1], axis=-1)  # (nu, nv) 3D cell diagonals

    # 1-2: classify all cells at once (16 configurations)
    corners = np.stack([inside[:-1, :-1], inside[1:, :-1], inside[1:, 1:], inside[:-1, 1:]], axis=-1)
    config = configuration(corners)

    # crossings to find: (p, q) parameter side endpoints; segments refer to crossing ids
    side_p: list[tuple[float, float]] = []
    side_q: list[tuple[float, float]] = []
    cross_id: dict[tuple, int] = {}

    def crossing(p: tuple[float, float], q: tuple[float, float]) -> int:
        key = (p, q) if p <= q else (q, p)
        k = cross_id.get(key)
        if k is None:
            k = cross_id[key] = len(side_p)
            side_p.append(key[0])
            side_q.append(key[1])
        return k

    seg_pairs: list[tuple[int, int]] = []
    seg_delta: list[float] = []
    n_amb = 0

    def emit(u0: float, u1: float, v0: float, v1: float, cfg: int, depth: int, dl: float) -> None:
        # sequential over the (few) cells the border crosses; D cells recurse
        nonlocal n_amb
        cls = classify(cfg)
        if cls == CLASS_A:
            return
        cs = [(u0, v0), (u1, v0), (u1, v1), (u0, v1)]
        if cls == CLASS_D and depth < max_split:
            n_amb += 1
            um, vm = 0.5 * (u0 + u1), 0.5 * (v0 + v1)
            pts = np.array([[um, v0], [u1, vm], [um, v1], [u0, vm], [um, vm]])
            w = model.W(pts[:, 0], pts[:, 1]) >= 0
            ins = [(cfg >> k) & 1 for k in range(4)]
            s0, s1, s2, s3, cen = (int(x) for x in w)
            for (a0, a1, b0, b1), cc in (((u0, um, v0, vm), (ins[0], s0, cen, s3)),
                                         ((um, u1, v0, vm), (s0, ins[1], s1, cen)),
                                         ((um, u1, vm, v1), (cen, s1, ins[2], s2)),
                                         ((u0, um, vm, v1), (s3, cen, s2, ins[3]))):
                emit(a0, a1, b0, b1, cc[0] | cc[1] << 1 | cc[2] << 2 | cc[3] << 3, depth + 1, dl)
            return
        centre = False
        if cls == CLASS_D:
            centre = bool(model.W(np.array([0.5 * (u0 + u1)]), np.array([0.5 * (v0 + v1)]))[0] >= 0)
        for s0, s1 in cell_segments(cfg, centre):
            seg_pairs.append((crossing(cs[s0], cs[(s0 + 1) % 4]), crossing(cs[s1], cs[(s1 + 1) % 4])))
            seg_delta.append(dl)

    for i, j in np.argwhere((config != 0) & (config != 15)):
        emit(float(gu[i]), float(gu[i + 1]), float(gv[j]), float(gv[j + 1]), int(config[i, j]), 0,
             delta * float(diag3[i, j]))

    # the sides of P: grid edges along them where W >= 0, cut at the crossings. Grid nodes get
    # ids after the crossings (NODE + k until the crossings are counted).
    node_id: dict[tuple[float, float], int] = {}
    extra: list[tuple[float, float]] = []
    NODE = 1 << 40

    def node(p: tuple[float, float]) -> int:
        k = node_id.get(p)
        if k is None:
            k = node_id[p] = NODE + len(extra)
            extra.append(p)
        return k

    segs: list[tuple[int, int, int]] = [(a, b, CURVE) for a, b in seg_pairs]
    deltas = list(seg_delta)
    nu, nv = len(gu) - 1, len(gv) - 1
    fu, fv = [float(x) for x in gu], [float(x) for x in gv]
    sides = [
        (SIDE_VC, [((fu[i], fv[0]), (fu[i + 1], fv[0]), inside[i, 0], inside[i + 1, 0]) for i in range(nu)]),
        (SIDE_UB, [((fu[-1], fv[j]), (fu[-1], fv[j + 1]), inside[-1, j], inside[-1, j + 1]) for j in range(nv)]),
        (SIDE_VD, [((fu[i + 1], fv[-1]), (fu[i], fv[-1]), inside[i + 1, -1], inside[i, -1]) for i in range(nu)]),
        (SIDE_UA, [((fu[0], fv[j + 1]), (fu[0], fv[j]), inside[0, j + 1], inside[0, j]) for j in range(nv)]),
    ]
    for kind, edges in sides:  # counter-clockwise around P: the kept region on the left
        for p, q, ip, iq in edges:
            if ip and iq:
                segs.append((node(p), node(q), kind))
            elif ip or iq:
                c = crossing(p, q)
                segs.append((node(p), c, kind) if ip else (c, node(q), kind))
            else:
                continue
            deltas.append(0.0)

    # root finding on W along the crossed sides (vectorised)
    cross_pts = model.bisect(np.array(side_p).reshape(-1, 2), np.array(side_q).reshape(-1, 2))
    points = np.vstack([cross_pts, np.array(extra, dtype=np.float64).reshape(-1, 2)])
    S = np.array([s[:2] for s in segs], dtype=np.int64).reshape(-1, 2)
    S = np.where(S >= NODE, S - NODE + len(cross_pts), S)
    K = np.array([s[2] for s in segs], dtype=np.int64)
    D = np.array(deltas)
    # a split (D) cell and its unsplit neighbour find the same crossing on their common side
    # through different brackets: identify points that agree to 1e-11 of the domain
    a_, b_, c_, d_ = surf.domain
    scale = np.array([b_ - a_, d_ - c_])
    key = np.round((points - [a_, c_]) / scale / 1e-11).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    points = points[first]
    S = inv.reshape(-1)[S]

    points, S, K, merged = _merge_short(model, points, S, K, D)
    S, K, points, open_ends = _compact(points, S, K)
    return Border(points, S, K, _chains(S), gu, gv, n_amb, merged, open_ends)


def _merge_short(model: HybridModel, points: NDArray, S: NDArray, K: NDArray, D: NDArray
                 ) -> tuple[NDArray, NDArray, NDArray, int]:
    """§2 step 3: an edge e = (w1, w2) with d(w1, w2) < δ is removed and w2 merged into w1.

    Only curve edges are merged; vertices on the sides of P (and junctions) stay where they are.
    Sequential (each merge changes the neighbours' lengths).
    """
    if not len(S):
        return points, S, K, 0
    a, b, c, d = model.surface.domain
    on_side = ((np.abs(points[:, 0] - a) < 1e-14 * (b - a)) | (np.abs(points[:, 0] - b) < 1e-14 * (b - a))
               | (np.abs(points[:, 1] - c) < 1e-14 * (d - c)) | (np.abs(points[:, 1] - d) < 1e-14 * (d - c)))
    deg = np.bincount(S.ravel(), minlength=len(points))
    fixed = on_side | (deg != 2)
    P3 = model.surface(points[:, 0], points[:, 1])
    rep = np.arange(len(points))

    def find(x: int) -> int:
        while rep[x] != x:
            rep[x] = rep[rep[x]]
            x = rep[x]
        return int(x)

    merged = 0
    for s in np.flatnonzero(K == CURVE):
        w1, w2 = find(int(S[s, 0])), find(int(S[s, 1]))
        if w1 == w2:
            continue
        if np.linalg.norm(P3[w1] - P3[w2]) >= D[s]:  # d(w1, w2) = |R(w1) − R(w2)|  (4)
            continue
        if fixed[w2] and fixed[w1]:
            continue
        if fixed[w2]:
            w1, w2 = w2, w1
        rep[w2] = w1
        merged += 1
    S2 = np.array([[find(int(x)) for x in row] for row in S], dtype=np.int64).reshape(-1, 2)
    keep = S2[:, 0] != S2[:, 1]
    # drop duplicated segments (two merges closing a tiny loop)
    S2, K2 = S2[keep], K[keep]
    _, first = np.unique(np.sort(S2, axis=1), axis=0, return_index=True)
    first = np.sort(first)
    return points, S2[first], K2[first], merged


def _compact(points: NDArray, S: NDArray, K: NDArray) -> tuple[NDArray, NDArray, NDArray, int]:
    used = np.unique(S.ravel())
    remap = -np.ones(len(points), dtype=np.int64)
    remap[used] = np.arange(len(used))
    S2 = remap[S]
    deg_out = np.bincount(S2[:, 0], minlength=len(used))
    deg_in = np.bincount(S2[:, 1], minlength=len(used))
    open_ends = int(np.sum(deg_out != deg_in))
    return S2, K, points[used], open_ends


def _chains(S: NDArray[np.int64]) -> list[NDArray[np.int64]]:
    """Split the directed segments into polylines (closed loops repeat their first vertex)."""
    nxt: dict[int, list[int]] = {}
    indeg: dict[int, int] = {}
    for a, b in S.tolist():
        nxt.setdefault(a, []).append(b)
        indeg[b] = indeg.get(b, 0) + 1
    used: set[tuple[int, int]] = set()
    out: list[NDArray[np.int64]] = []
    starts = [a for a in nxt if indeg.get(a, 0) != 1 or len(nxt[a]) != 1] + list(nxt)
    for s in starts:
        for b0 in nxt.get(s, []):
            if (s, b0) in used:
                continue
            chain = [s]
            a, b = s, b0
            while (a, b) not in used:
                used.add((a, b))
                chain.append(b)
                if len(nxt.get(b, [])) != 1 or indeg.get(b, 0) != 1:
                    break
                a, b = b, nxt[b][0]
            out.append(np.array(chain, dtype=np.int64))
    return out

"""Normalisation: turn any triangle soup into a clean incomplete model (ICADM).

Real reconstructions are not clean: they hold degenerate faces, duplicated faces (often with the
opposite winding), edges with more than two faces, islands wound inconsistently and tiny
fragments touching the surface only at a vertex. ``normalize`` keeps every face that can be part
of an incomplete model, orients each island consistently, splits vertices where separate fans
meet, and sets the rest aside, each face with its reason. Nothing silently disappears: the
vertices of set-aside faces that no kept face uses become free points.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from numpy.typing import NDArray

from .mesh import Icadm, Mesh, SetAside, face_cross, face_normals
from .topology import edge_table, face_adjacency, halfedges, islands


def _degenerate(v: NDArray[np.float64], f: NDArray[np.int64], rel_area: float) -> tuple[NDArray, NDArray]:
    repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    area2 = np.linalg.norm(face_cross(v, f), axis=1)
    diag = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0))) if len(v) else 0.0
    flat = ~repeated & (area2 <= 2 * rel_area * diag * diag)
    return repeated, flat


def _directed_counts(f: NDArray[np.int64], nv: int) -> tuple[NDArray, NDArray]:
    he = halfedges(f)
    keys = he[:, 0] * nv + he[:, 1]
    uk, cnt = np.unique(keys, return_counts=True)
    return uk, cnt


def _lookup(uk: NDArray, cnt: NDArray, keys: NDArray) -> NDArray:
    i = np.clip(np.searchsorted(uk, keys), 0, max(len(uk) - 1, 0))
    if not len(uk):
        return np.zeros(keys.shape, dtype=np.int64)
    return np.where(uk[i] == keys, cnt[i], 0)


def _orientation_parity(f: NDArray[np.int64], alive: NDArray[np.bool_]) -> tuple[NDArray, NDArray]:
    """BFS over manifold edges: parity (flip or not) per face and the faces reached in BFS order.

    Returns (parity, conflict_faces): parity[f] = True means face f must be flipped to agree
    with the first face of its island; conflict_faces are faces that meet a neighbour with
    the wrong winding whatever the flips (the island is not orientable there).
    """
    idx = np.flatnonzero(alive)
    sub = f[idx]
    pairs = face_adjacency(sub, manifold_only=True)
    # same direction on the shared edge => one of the two must be flipped
    he = halfedges(sub).reshape(-1, 3, 2)
    a, b = he[pairs[:, 0]], he[pairs[:, 1]]
    same = (a[:, :, None, 0] == b[:, None, :, 0]) & (a[:, :, None, 1] == b[:, None, :, 1])
    same_dir = same.any(axis=(1, 2))
    n = len(sub)
    if not same_dir.any():  # consistently wound already (the usual input): nothing to flip, no conflict
        return np.zeros(len(f), dtype=bool), np.zeros(0, dtype=np.int64)
    nbrs: list[list[tuple[int, bool]]] = [[] for _ in range(n)]
    for (p, q), s in zip(pairs.tolist(), same_dir.tolist()):
        nbrs[p].append((q, s))
        nbrs[q].append((p, s))
    parity = np.zeros(n, dtype=bool)
    seen = np.zeros(n, dtype=bool)
    conflicts: list[int] = []
    # sequential BFS: parity propagates along a spanning tree
    for s0 in range(n):
        if seen[s0]:
            continue
        seen[s0] = True
        dq = deque([s0])
        while dq:
            x = dq.popleft()
            for y, s in nbrs[x]:
                want = parity[x] ^ s
                if not seen[y]:
                    seen[y] = True
                    parity[y] = want
                    dq.append(y)
                elif parity[y] != want:
                    conflicts.append(max(x, y))
    full = np.zeros(len(f), dtype=bool)
    full[idx] = parity
    return full, idx[np.unique(np.array(conflicts, dtype=np.int64))] if conflicts else np.zeros(0, dtype=np.int64)


def _sheet_links(v: NDArray[np.float64], f: NDArray[np.int64], alive: NDArray[np.bool_]) -> NDArray[np.int64]:
    """(K, 3) links (face, face, edge id) between faces that continue each other across an edge.

    Edges with two faces link them. Around an edge with more faces, faces are paired greedily by
    smoothness: opposite windings on the edge (consistent neighbours) with the largest dot
    product of normals first; a pair with equal windings (one will be flipped) scores the
    negated dot product minus a penalty. Unpaired faces keep the edge as a boundary.
    Face and edge ids refer to ``f`` and to ``edge_table(f[alive])``.
    """
    ids = np.flatnonzero(alive)
    if not len(ids):
        return np.zeros((0, 3), dtype=np.int64)
    sub = f[ids]
    et = edge_table(sub)
    he = halfedges(sub)
    e_of = et.halfedge_edge
    order = np.argsort(e_of, kind="stable")
    es = e_of[order]
    starts = np.flatnonzero(np.r_[True, es[1:] != es[:-1]])
    ends = np.r_[starts[1:], len(es)]
    cnt = ends - starts
    out = []
    two = cnt == 2
    if two.any():
        a = order[starts[two]]
        b = order[starts[two] + 1]
        out.append(np.stack([ids[a // 3], ids[b // 3], es[starts[two]]], axis=1))
    many = np.flatnonzero(cnt > 2)
    if len(many):
        # patches through two-face edges: faces of large patches pair with each other first
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components

        pr = face_adjacency(sub, manifold_only=True)
        g = sp.coo_matrix((np.ones(len(pr)), (pr[:, 0], pr[:, 1])), shape=(len(sub), len(sub)))
        _, plab = connected_components(g, directed=False)
        psize = np.bincount(plab)[plab]
        nrm = face_normals(v, sub)
        extra = []
        for k in many.tolist():
            hs = order[starts[k]:ends[k]]
            fs = hs // 3
            direction = he[hs, 0] < he[hs, 1]
            cand = []
            for i in range(len(hs)):
                for j in range(i + 1, len(hs)):
                    d = float(nrm[fs[i]] @ nrm[fs[j]])
                    sc = d if direction[i] != direction[j] else -d - 1.0
                    cand.append((min(psize[fs[i]], psize[fs[j]]), sc, i, j))
            used: set[int] = set()
            for _, _, i, j in sorted(cand, reverse=True):
                if i not in used and j not in used:
                    used.update((i, j))
                    extra.append((ids[fs[i]], ids[fs[j]], es[starts[k]]))
        if extra:
            out.append(np.array(extra, dtype=np.int64))
    return np.vstack(out) if out else np.zeros((0, 3), dtype=np.int64)


def _split_fans(f: NDArray[np.int64], alive: NDArray[np.bool_], links: NDArray[np.int64],
                nv: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Give each fan of faces around a vertex its own vertex (copies appended after ``nv``).

    Corners (face, k) of one vertex are joined when their faces are linked across an edge
    through that vertex. Each class of corners is one output vertex; the largest class of a
    vertex keeps its index. Returns the new face array and vertex_origin (new -> input vertex).
    """
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    out = f.copy()
    nf = len(f)
    if not nf or not alive.any():  # nothing to split (every face set aside: a file of degenerate faces)
        return out, np.arange(nv, dtype=np.int64)
    corner = np.arange(3 * nf).reshape(nf, 3)
    rows, cols = [], []
    if len(links):
        fa, fb = f[links[:, 0]], f[links[:, 1]]
        for ka in range(3):
            for kb in range(3):
                m = fa[:, ka] == fb[:, kb]
                rows.append(corner[links[m, 0], ka])
                cols.append(corner[links[m, 1], kb])
    r = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    c = np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64)
    g = sp.coo_matrix((np.ones(len(r)), (r, c)), shape=(3 * nf, 3 * nf))
    _, cls = connected_components(g, directed=False)
    live = np.repeat(alive, 3)
    vert = f.ravel()
    # per vertex: the class with the most corners keeps the index
    lc = cls[live]
    lv = vert[live]
    uc, inv, ccount = np.unique(lc, return_inverse=True, return_counts=True)
    cls_vert = np.zeros(len(uc), dtype=np.int64)
    cls_vert[inv] = lv
    order = np.lexsort((uc, -ccount, cls_vert))
    first = np.r_[True, cls_vert[order][1:] != cls_vert[order][:-1]]
    new_index = np.empty(len(uc), dtype=np.int64)
    new_index[order[first]] = cls_vert[order[first]]
    extra = order[~first]
    new_index[extra] = nv + np.arange(len(extra))
    flat = out.ravel()
    flat[live] = new_index[inv]
    vertex_origin = np.concatenate([np.arange(nv), cls_vert[extra]]).astype(np.int64)
    return flat.reshape(nf, 3), vertex_origin


def normalize(vertices: NDArray[np.float64], faces: NDArray[np.int64], *,
              extra_points: NDArray[np.float64] | None = None,
              degenerate_area: float = 1e-14,
              tiny_fragment: int = 8,
              source: str = "") -> Icadm:
    """Build a clean ICADM from raw vertices (V, 3) and faces (F, 3) as read from a file.

    degenerate_area: faces with area below this fraction of the squared bounding-box diagonal
        are set aside as degenerate.
    tiny_fragment: an island of at most this many faces that touches another island only at
        vertices is set aside (its faces are most likely reconstruction debris).
    """
    mesh_in = Mesh(vertices, faces)  # validates shapes, finiteness and indices
    v, f = mesh_in.vertices, mesh_in.faces.copy()
    nv = len(v)
    alive = np.ones(len(f), dtype=bool)
    reasons: dict[int, str] = {}

    def drop(ids: NDArray | list[int], why: str | list[str]) -> None:
        ids = np.asarray(ids, dtype=np.int64)
        whys = [why] * len(ids) if isinstance(why, str) else why
        for i, w in zip(ids.tolist(), whys):
            if alive[i]:
                alive[i] = False
                reasons[i] = w

    # 1. degenerate faces
    if len(f):
        repeated, flat = _degenerate(v, f, degenerate_area)
        drop(np.flatnonzero(repeated), "degenerate: a vertex is repeated")
        drop(np.flatnonzero(flat), "degenerate: zero area")

    # 2. duplicate faces (same three vertices): keep the copy whose winding agrees with its
    #    neighbours (the faces that are not duplicated)
    ids = np.flatnonzero(alive)
    if len(ids):
        key = np.sort(f[ids], axis=1)
        if nv < 2_000_000:  # one int64 per face (a row-wise unique sorts far slower)
            key = (key[:, 0] * nv + key[:, 1]) * nv + key[:, 2]
            _, inv, cnt = np.unique(key, return_inverse=True, return_counts=True)
        else:
            _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        inv = inv.ravel()
        dup = cnt[inv] > 1
        if dup.any():
            single = ids[~dup]
            uk, uc = _directed_counts(f[single], nv)
            he = halfedges(f[ids[dup]]).reshape(-1, 3, 2)
            agree = _lookup(uk, uc, he[:, :, 1] * nv + he[:, :, 0]).sum(axis=1)
            disagree = _lookup(uk, uc, he[:, :, 0] * nv + he[:, :, 1]).sum(axis=1)
            score = agree - disagree
            groups: dict[int, list[tuple[int, int]]] = {}
            for fid, g, sc in zip(ids[dup].tolist(), inv[dup].tolist(), score.tolist()):
                groups.setdefault(g, []).append((fid, sc))
            for members in groups.values():
                keep = max(members, key=lambda m: (m[1], -m[0]))[0]
                kt = f[keep].tolist()
                for fid, _ in members:
                    if fid == keep:
                        continue
                    ft = f[fid].tolist()
                    k = kt.index(ft[0])
                    same = kt[k:] + kt[:k] == ft
                    drop([fid], f"duplicate of face {keep} ({'same' if same else 'opposite'} orientation)")

    # 3. edges with more than two faces: pair the faces around each such edge into sheets (the
    #    smoothest continuations first) and cut the edge between sheets; faces left unpaired
    #    become boundary there. No face is dropped for this.
    links = _sheet_links(v, f, alive)

    # 4. split vertices where separate fans (or sheets) meet; tiny fragments that touch a larger
    #    island only at vertices are set aside
    f_split, vertex_origin = _split_fans(f, alive, links, nv)
    ids = np.flatnonzero(alive)
    split_islands = None  # (faces, count, labels) of the islands of f_split[ids], reused in step 5
    if len(ids):
        n_isl, lab = islands(f_split[ids])
        split_islands = (ids, n_isl, lab)
        size = np.bincount(lab, minlength=n_isl)
        # (original vertex, island) pairs; only vertices shared by two or more islands matter
        code = np.unique(vertex_origin[f_split[ids]].ravel().astype(np.int64) * n_isl + np.repeat(lab, 3))
        pairs = np.stack([code // n_isl, code % n_isl], axis=1)
        shared = np.flatnonzero(np.bincount(pairs[:, 0]) > 1)
        n_alive = int(alive.sum())
        for vo in shared.tolist():
            isl = pairs[pairs[:, 0] == vo, 1].tolist()
            big = max(isl, key=lambda i: (size[i], -i))
            for i in isl:
                if i != big and size[i] <= tiny_fragment and size[i] < size[big]:
                    drop(ids[lab == i], f"fragment of {int(size[i])} faces attached to island "
                                        f"{big} only at vertex {vo}")
        if int(alive.sum()) != n_alive:  # fragments went: the sheets and fans change
            links = _sheet_links(v, f, alive)
            f_split, vertex_origin = _split_fans(f, alive, links, nv)
            split_islands = None

    # 5. orientation per island: flip the minority so neighbours agree; set aside what cannot be
    #    oriented (non-orientable strips)
    flipped = np.zeros(len(f), dtype=bool)
    f = f_split
    parity = np.zeros(len(f), dtype=bool)
    for _ in range(10):
        parity, conflicts = _orientation_parity(f, alive)
        if not len(conflicts):
            break
        drop(conflicts, "cannot be oriented consistently with its neighbours (non-orientable)")
    ids = np.flatnonzero(alive)
    if len(ids):
        if split_islands is not None and np.array_equal(split_islands[0], ids):
            _, n_isl, lab = split_islands  # the same faces as step 4 (nothing set aside since): same islands
        else:
            n_isl, lab = islands(f[ids])
        par = parity[ids]
        flip_count = np.bincount(lab, weights=par.astype(float), minlength=n_isl)
        size = np.bincount(lab, minlength=n_isl)
        invert = flip_count > size / 2  # flip the smaller parity class of each island
        do_flip = par ^ invert[lab]
        flipped[ids] = do_flip
        f[ids[do_flip]] = f[ids[do_flip]][:, ::-1]
    new_vertices = v[vertex_origin[nv:]]

    all_v = np.vstack([v, new_vertices]) if len(new_vertices) else v
    kept = np.flatnonzero(alive)
    mesh = Mesh(all_v, f[kept])
    used = mesh.referenced()
    free_origin = np.flatnonzero(~used[:nv])
    free = all_v[free_origin]
    if extra_points is not None and len(extra_points):
        extra = np.asarray(extra_points, dtype=np.float64).reshape(-1, 3)
        free = np.vstack([free, extra])
        free_origin = np.concatenate([free_origin, np.full(len(extra), -1)])
    set_aside = tuple(SetAside(i, tuple(int(x) for x in mesh_in.faces[i]), reasons[i])  # type: ignore[misc]
                      for i in sorted(reasons))
    return Icadm(mesh=mesh, free_points=free, face_origin=kept, vertex_origin=vertex_origin,
                 free_origin=free_origin, set_aside=set_aside, flipped=flipped[kept], source=source)


def set_aside_summary(model: Icadm) -> dict[str, int]:
    """Counts of set-aside faces by the first words of their reason."""
    out: dict[str, int] = {}
    for s in model.set_aside:
        k = s.reason.split(" (")[0].split(" of face")[0]
        k = k.split(" already")[0] if k.startswith("non-manifold") else k
        k = "non-manifold edge" if k.startswith("non-manifold edge") else k
        k = "fragment attached only at a vertex" if k.startswith("fragment") else k
        out[k] = out.get(k, 0) + 1
    return out

"""Where a repaired surface has its handles: a greedy basis of its first homology through a root
vertex, cycle by cycle, for finding the one handle too many on a sweep cut.

    python -m bench.handles MODEL[+STYLE]:SEED:IT [--mode light|full] [--loops 3,5]

For a closed, connected surface of genus g the basis has 2 g cycles, each the shortest loop through
the root in its homology class as far as the greedy construction goes (Erickson and Whittlesey,
"Greedy optimal homotopy and homology generators", SODA 2005): a shortest-path tree from the root,
a maximum spanning tree of the dual graph on the other edges weighted by the length of the cycle
each closes, and the 2 g edges left over, each closing one cycle. Rooted near a small spurious
handle, two of the cycles are short (the handle's two generators); rooted far from it they run
there and back. The command roots the basis at each loop of the cut in turn (the loop's vertex
nearest its centre) and prints the cycles' lengths: the loop with the most short cycles is where
to look. Not part of the test suite's timing; a debugging aid for the sweep's misses, like
``bench.explain``.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra, minimum_spanning_tree

from algorithms.topology import edge_table, face_adjacency


@dataclass(frozen=True)
class Cycle:
    length: float  # of the closed walk: tree path root -> a, the edge a-b, tree path b -> root
    edge: tuple[int, int]  # the edge outside both trees that closes it


def homology_cycles(vertices: NDArray[np.float64], faces: NDArray[np.int64], root: int) -> list[Cycle]:
    """The greedy homology basis of a closed, connected triangle mesh through ``root``, shortest
    first (2 genus cycles; none on a sphere)."""
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    et = edge_table(F)
    if not np.all(et.counts == 2):
        raise ValueError("homology_cycles needs a closed surface (every edge on two faces)")
    E, n = et.edges, len(V)
    w = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    dist, pred = dijkstra(coo_matrix((w, (E[:, 0], E[:, 1])), shape=(n, n)).tocsr(), directed=False,
                          indices=root, return_predecessors=True)
    if not np.all(np.isfinite(dist[np.unique(F)])):
        raise ValueError("homology_cycles needs a connected surface")
    child = np.flatnonzero(pred >= 0)
    in_tree = np.isin(E[:, 0] * n + E[:, 1],
                      np.minimum(child, pred[child]) * n + np.maximum(child, pred[child]))
    sigma = dist[E[:, 0]] + dist[E[:, 1]] + w  # the length of the cycle each edge closes
    sides = face_adjacency(F)  # closed: one pair of faces per edge, in the edges' order
    # the dual graph on the edges outside the tree, its maximum spanning tree by sigma: of parallel
    # dual edges (two faces sharing two edges) only the longest cycle's can be in it
    rest = np.flatnonzero(~in_tree)
    rest = rest[np.argsort(-sigma[rest], kind="stable")]
    a, b = sides[rest].min(axis=1), sides[rest].max(axis=1)
    _, first = np.unique(a * len(F) + b, return_index=True)
    rep = rest[first]
    weight = sigma[rep].max() + 1.0 - sigma[rep]  # positive, smallest for the longest cycle
    cotree = minimum_spanning_tree(coo_matrix((weight, (a[first], b[first])), shape=(len(F), len(F))).tocsr())
    t = cotree.tocoo()
    in_cotree = rep[np.isin(a[first] * len(F) + b[first], np.minimum(t.row, t.col) * len(F) + np.maximum(t.row, t.col))]
    gens = np.setdiff1d(rest, in_cotree)
    gens = gens[np.argsort(sigma[gens], kind="stable")]
    return [Cycle(float(sigma[e]), (int(E[e, 0]), int(E[e, 1]))) for e in gens]


def main(argv: list[str] | None = None) -> int:
    from algorithms.boundary import summarize
    from algorithms.metrics import topology
    from algorithms.normalize import normalize
    from algorithms.params import FieldParams
    from algorithms.repair import RepairParams, repair
    from bench.sweep import cut_named

    ap = argparse.ArgumentParser(prog="python -m bench.handles", description=__doc__.split("\n\n")[0])
    ap.add_argument("cut", help="MODEL[+STYLE]:SEED:IT, as bench.sweep names its cuts")
    ap.add_argument("--mode", choices=("light", "full"), default="light")
    ap.add_argument("--loops", help="root at these loops only (comma-separated, as bench.explain numbers them)")
    a = ap.parse_args(argv)
    case = cut_named(a.cut)
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    frames = summarize(model).loops
    res = repair(model, RepairParams(field=FieldParams(mode=a.mode)))
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    t, truth = topology(F), topology(np.asarray(case.truth.faces))
    print(f"{a.cut} ({a.mode}): output genus {t.genus}, truth {truth.genus}")
    if not (t.watertight and t.components == 1):
        print("not one closed piece: no basis")
        return 1
    ks = [int(k) for k in a.loops.split(",")] if a.loops else range(len(frames))
    for k in ks:
        # the loop's vertex nearest its centre (input vertices keep their positions in the output)
        P = frames[k].points
        p = P[np.argmin(np.linalg.norm(P - P.mean(axis=0), axis=1))]
        root = int(np.argmin(np.linalg.norm(V - p, axis=1)))
        cycles = homology_cycles(V, F, root)
        print(f"  loop {k} (root vertex {root}): " + ", ".join(f"{cy.length:.3g}" for cy in cycles))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

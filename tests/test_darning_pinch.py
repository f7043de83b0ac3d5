"""Pinched holes: a hole whose border passes twice through one vertex (normalisation splits that
vertex into copies, one per fan). darn fills the hole's simple parts one by one and joins the
copies again, so the filled surface is a manifold with one vertex per point, as the intact one was.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from algorithms import metrics
from algorithms.darning import darn, fill_holes, pinches, split_pinched
from algorithms.metrics import topology
from algorithms.normalize import normalize
from algorithms.repair import repair
from algorithms.topology import boundary_loops, edge_table


def test_split_pinched_cuts_off_the_innermost_part_first():
    # 10 and 11 are copies of 1 and 3: the loop 0 1 2 3 4 11 5 10 6 is pinched twice
    loop = np.array([0, 1, 2, 3, 4, 11, 5, 10, 6])
    parts = split_pinched(loop, np.array([[10, 1], [11, 3]]))
    # 3 ... 3 (the slit 3 4 3, no face), then 1 2 3 5 (closing to 10 = 1), then the rest
    assert [p.tolist() for p in parts] == [[1, 2, 3, 5], [0, 1, 6]]


def test_split_pinched_drops_slits():
    # a slit: 0 -> 1 -> 0' (0' = 5 a copy of 0) closes without a face
    parts = split_pinched(np.array([0, 1, 5, 2, 3]), np.array([[5, 0]]))
    assert [p.tolist() for p in parts] == [[0, 2, 3]]


def test_pinches_finds_coincident_copies_only():
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, 0], [0.5, 0.5, 0.0]], dtype=float)
    assert pinches(v, np.array([0, 1, 2, 4, 3])).tolist() == [[4, 1]]
    assert pinches(v, np.array([0, 1, 2, 3, 5])).shape == (0, 2)


def _pinched_torus():
    """A torus with a bow-tie hole: two blocks of 2 x 2 grid cells removed that touch only at the
    vertex p, one up and to the right of p, one down and to the left. The faces left around p are
    two fans (up-left, down-right), so normalisation splits p, and the hole is one loop through p
    twice (the up-left fan leads from one block's border to the other's)."""
    n_major, n_minor = 32, 16
    t = trimesh.creation.torus(1.0, 0.4, major_sections=n_major, minor_sections=n_minor)
    V, F = np.asarray(t.vertices), np.asarray(t.faces)
    p = 0  # on the outer equator, major angle 0, minor angle 0
    c = V[F].mean(axis=1)
    col = np.floor(np.arctan2(c[:, 1], c[:, 0]) / (2 * np.pi / n_major)).astype(int)
    row = np.floor(np.arctan2(c[:, 2], np.hypot(c[:, 0], c[:, 1]) - 1.0) / (2 * np.pi / n_minor)).astype(int)
    band = (np.isin(col, [0, 1]) & np.isin(row, [0, 1])) | (np.isin(col, [-2, -1]) & np.isin(row, [-2, -1]))
    return V, F, band, p


def _vertex_manifold(F: np.ndarray, v: int) -> bool:
    """Whether v's faces form one disc: their edges opposite v make one cycle."""
    star = F[(F == v).any(axis=1)]
    link = np.array([[x for x in f if x != v] for f in star])
    ids, inv = np.unique(link, return_inverse=True)
    inv = inv.reshape(-1, 2)
    deg = np.bincount(inv.ravel(), minlength=len(ids))
    g = coo_matrix((np.ones(len(inv)), (inv[:, 0], inv[:, 1])), shape=(len(ids), len(ids)))
    return bool(np.all(deg == 2) and connected_components(g, directed=False)[0] == 1)


def test_the_pinched_hole_is_one_loop_through_a_split_vertex():
    V, F, cut, p = _pinched_torus()
    model = normalize(V, F[~cut])
    assert model.mesh.n_vertices == len(V) + 1  # p split into two copies
    loops = boundary_loops(model.mesh.faces)
    assert len(loops) == 1
    lp = loops[0]
    assert len(pinches(model.mesh.vertices, lp)) == 1


@pytest.mark.parametrize("method", ["liepa", "liepa-fair"])
def test_darn_joins_the_copies_of_a_pinched_hole(method):
    V, F, cut, p = _pinched_torus()
    model = normalize(V, F[~cut])
    copy = model.mesh.n_vertices - 1
    (lp,) = boundary_loops(model.mesh.faces)
    patch = darn(model.mesh.vertices, model.mesh.faces, lp, method=method)
    assert patch.merged.tolist() == [[copy, p]]
    out, _ = fill_holes(model.mesh, method=method)
    t = metrics.topology(out.faces)
    assert t.watertight and t.components == 1 and t.genus == 1
    assert copy not in out.faces  # the copy is joined to p again ...
    assert _vertex_manifold(out.faces, p)  # ... and p is a disc
    # every input face is kept with its coordinates (the copy's faces now name p, at the same point)
    assert np.array_equal(out.vertices[out.faces[:len(model.mesh.faces)]], model.mesh.vertices[model.mesh.faces])
    # the removed faces: two squares of the torus' own grid; no sliver is needed to fill them
    ang = metrics.min_angles(out.vertices, out.faces[len(model.mesh.faces):])
    assert ang.min() > 20.0


def test_repair_of_a_pinched_hole_has_one_vertex_per_point():
    V, F, cut, p = _pinched_torus()
    model = normalize(V, F[~cut])
    res = repair(model)
    out = res.mesh
    t = metrics.topology(out.faces)
    assert t.watertight and t.components == 1 and t.genus == 1
    # no two output vertices at one point (before, both copies stayed, joined by slivers)
    rounded = np.round(out.vertices, 9)
    assert len(np.unique(rounded, axis=0)) == len(out.vertices)
    q = int(np.flatnonzero(np.all(np.isclose(out.vertices, V[p], atol=1e-12), axis=1))[0])
    assert _vertex_manifold(out.faces, q)
    assert metrics.min_angles(out.vertices, out.faces[res.new_faces]).min() > 15.0


def _frame_and_piece():
    """A flat 6 x 6 grid's outer ring of cells (the surface around a 4 x 4 hole) and one triangle
    inside the hole that touches the hole's border only at its corner c = (1, 1): the hole is an
    annulus whose two borders touch at c. Returns vertices, faces (frame then triangle), the hole's
    walk (through c twice, each pass from the frame's fan to the triangle's or back) and c."""
    ij = np.array([(i, j) for j in range(7) for i in range(7)], dtype=float)
    V = np.c_[ij, np.zeros(len(ij))]

    def at(i, j):
        return 7 * j + i

    frame = []
    for j in range(6):
        for i in range(6):
            if i in (0, 5) or j in (0, 5):
                a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
                frame += [(a, b, c), (a, c, d)]
    c = at(1, 1)
    piece = [(c, at(3, 2), at(2, 3))]  # counter-clockwise seen from +z, like the frame
    F = np.array(frame + piece)
    inner = next(lp for lp in boundary_loops(np.array(frame)) if c in lp)
    k = int(np.flatnonzero(inner == c)[0])
    around = np.roll(inner, -k).tolist()  # c, a1, ..., ak
    (tri,) = boundary_loops(np.array(piece))
    t = np.roll(tri, -int(np.flatnonzero(tri == c)[0])).tolist()  # c, t1, t2
    return V, F, np.array(around + t), c


def test_split_pinched_keeps_a_pinch_whose_passes_are_right():
    V, F, walk, c = _frame_and_piece()
    # without the faces: cut at c, the triangle's own loop a part of its own (a pillow over it)
    assert sorted(map(len, split_pinched(walk, np.zeros((0, 2), int)))) == [3, len(walk) - 3]
    # with them: each pass of c runs from one fan to the other, and a cut would make both turn
    # around one fan: the walk stays whole
    (part,) = split_pinched(walk, np.zeros((0, 2), int), F)
    assert part.tolist() == walk.tolist()


@pytest.mark.parametrize("method", ["liepa", "liepa-fair"])
def test_darn_fills_round_a_piece_touching_the_border(method):
    """The annulus is filled in one, c as two corners: the patch covers the hole minus the
    triangle (area 16 - 1.5), and c is a disc. Before, the triangle was closed by its own face
    reversed and the whole square filled over it."""
    V, F, walk, c = _frame_and_piece()
    patch = darn(V, F, walk, method=method)
    v, f = np.vstack([V, patch.new_vertices]), patch.faces
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum()
    assert area == pytest.approx(16 - 1.5, abs=1e-9)
    every = np.vstack([F, f])
    assert edge_table(every).counts.max() == 2
    assert _vertex_manifold(every, c)
    assert topology(every).components == 1


def test_copies_whose_merge_gives_an_edge_three_faces_stay_apart():
    """mergeable: copy 5 of vertex 1 has a face with vertex 3, as vertex 1 has; merged, the edge 1-3
    would have two faces plus the fill's on the loop edge 3 -> 1. Copy 6 of vertex 2 shares no
    neighbour with it: merged."""
    from algorithms.darning import mergeable

    faces = np.array([[1, 3, 7], [5, 8, 3], [6, 9, 10]])
    loop = np.array([0, 1, 2, 3, 5, 4, 6])
    pairs = np.array([[5, 1], [6, 2]])
    assert mergeable(faces, loop, pairs).tolist() == [[6, 2]]
    # without the face at the copy, edge 1-3 has one face and the loop edge: both pairs merge
    assert mergeable(faces[[0, 2]], loop, pairs).tolist() == [[5, 1], [6, 2]]

"""Copies of one point joined into one vertex (algorithms/copies.py): the output must not touch
itself, since the scorer merges vertices by position."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from test_repair import assert_input_kept

from algorithms.copies import coincident_groups, join_copies
from algorithms.metrics import topology
from algorithms.normalize import normalize
from algorithms.params import FieldParams
from algorithms.repair import RepairParams, repair
from algorithms.topology import edge_table, euler_characteristic, vertex_fans
from bench.repair import merge_positions


def ring_of(F: np.ndarray, v: int) -> list[int]:
    """The link of an interior vertex, in the order of its faces."""
    nxt = {}
    for r in F[(F == v).any(axis=1)]:
        j = list(r).index(v)
        nxt[int(r[(j + 1) % 3])] = int(r[(j + 2) % 3])
    ring = [next(iter(nxt))]
    while len(ring) < len(nxt):
        ring.append(nxt[ring[-1]])
    return ring


def sweep_repair(name: str, mode: str = "light"):
    """The repair of the random cut MODEL:SEED:IT of bench/sweep.py."""
    from bench.sweep import cut_named

    case = cut_named(name)
    return repair(normalize(case.vertices, case.faces, extra_points=case.free_points),
                  RepairParams(field=FieldParams(mode=mode)))


def assert_closed_once_merged(res, genus: int) -> None:
    """No two vertices of the output at one point, and with them merged by position (as the scorer
    loads an output) a closed manifold in one piece of ``genus``; every input face kept."""
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    assert not coincident_groups(V, F)
    topo = topology(merge_positions(V, F, 1e-9)[1])
    assert topo.watertight and topo.manifold_vertices and topo.components == 1 and topo.genus == genus
    assert_input_kept(res.model, res.mesh)


def vertex_split(F: np.ndarray, v: int, new: int, a: int, b: int) -> np.ndarray:
    """The inverse of contracting the edge (v, new): v keeps the faces on its ring from position a to
    b, ``new`` takes the rest, and the edge between them gets its two faces (appended last)."""
    ring = ring_of(F, v)
    n = len(ring)
    rows = [r for r in F.tolist() if v not in r]
    for i in range(n):
        owner = v if (i - a) % n < (b - a) % n else new
        rows.append([owner, ring[i], ring[(i + 1) % n]])
    rows += [[v, ring[b], new], [new, ring[a], v]]
    return np.asarray(rows, dtype=np.int64)


def copy_beyond_new_vertex(F: np.ndarray, v: int, c: int, w: int) -> np.ndarray:
    """v expanded into the path v - w - c: c is not adjacent to v."""
    F2 = vertex_split(F, v, w, 0, 3)
    ring = ring_of(F2, w)
    k = ring.index(v)
    n = len(ring)
    return vertex_split(F2, w, c, (k - 1) % n, (k + 2) % n)  # w keeps v and its two ring neighbours


def closed_manifold(F: np.ndarray) -> bool:
    return bool(np.all(edge_table(F).counts == 2)) and not vertex_fans(F)


@pytest.fixture
def sphere():
    s = trimesh.creation.icosphere(1)
    return np.asarray(s.vertices, dtype=np.float64), np.asarray(s.faces, dtype=np.int64)


@pytest.fixture
def expanded(sphere):
    """The sphere's vertex 0 expanded into 0 - w - c: c (index n) a copy at vertex 0's position, as
    normalisation makes them, w (n + 1) a vertex beside it. Returns (F, V2, F2, n, c, w)."""
    V, F = sphere
    n = len(V)
    c, w = n, n + 1
    return F, np.vstack([V, V[0], V[0] + 0.05]), copy_beyond_new_vertex(F, 0, c, w), n, c, w


def test_a_path_of_new_vertices_between_two_copies_is_contracted_back(expanded):
    F, V2, F2, n, c, w = expanded
    assert closed_manifold(F2) and euler_characteristic(F2) == 2
    assert [list(g) for g in coincident_groups(V2, F2)] == [[0, c]]
    # the scorer's view: merged by position, the edges from w to 0 and to c are one edge with four faces
    _, mf = merge_positions(V2, F2, 1e-9)
    assert edge_table(mf).counts.max() == 4
    got = join_copies(V2, F2, n_fixed=n + 1, n_fixed_faces=0)  # c is an input vertex, w a new one
    assert (got.joined, got.left) == (1, 0)
    assert closed_manifold(got.faces) and euler_characteristic(got.faces) == 2
    assert not np.isin(got.faces, [c, w]).any()
    # the contraction undoes the two splits: the sphere's own faces, as sets
    assert {frozenset(r) for r in got.faces.tolist()} == {frozenset(r) for r in F.tolist()}


def test_copies_with_no_new_vertex_between_them_are_joined_through_the_patch_faces(expanded):
    _, V2, F2, n, c, w = expanded
    # w is an input vertex now: no path of new vertices; the faces away from vertex 0 are the input's
    at = np.isin(F2, [0, c, w]).any(axis=1)
    order = np.r_[np.flatnonzero(~at), np.flatnonzero(at)]
    F3 = F2[order]
    fixed = int((~at).sum())
    got = join_copies(V2, F3, n_fixed=n + 2, n_fixed_faces=fixed)
    assert (got.joined, got.left) == (1, 0)
    assert closed_manifold(got.faces) and euler_characteristic(got.faces) == 2
    assert not np.isin(got.faces, [c]).any()
    np.testing.assert_array_equal(got.faces[:fixed], F3[:fixed])  # the input's faces, untouched, first


def test_a_join_that_would_remove_an_input_face_is_not_made(sphere):
    V, F = sphere
    n = len(V)
    c = n
    F2 = vertex_split(F, 0, c, 0, 3)  # an edge between the copies: its two faces would go
    V2 = np.vstack([V, V[0]])
    got = join_copies(V2, F2, n_fixed=n + 1, n_fixed_faces=len(F2))
    assert (got.joined, got.left) == (0, 1)
    np.testing.assert_array_equal(got.faces, F2)
    got = join_copies(V2, F2, n_fixed=n + 1, n_fixed_faces=len(F2) - 2)  # those two are patch faces
    assert (got.joined, got.left) == (1, 0)
    assert {frozenset(r) for r in got.faces.tolist()} == {frozenset(r) for r in F.tolist()}


@pytest.mark.parametrize("name", ["box:4:1", "capsule:1:0"])
def test_sweep_cuts_with_pinched_holes_come_back_without_copies(name):
    """Random cuts (bench/sweep.py) that leave vertices where two holes touch: before the joins the
    output was closed as written but kept copies of such a vertex (box 4:1: Euler 1 once merged by
    position; capsule 1:0: an edge with four faces, three pieces), which the scorer sees."""
    res = sweep_repair(name)
    assert_closed_once_merged(res, genus=0)
    assert "copies of a point joined into one vertex" in res.tunnel_note


def test_vertices_a_round_off_apart_are_one_point_and_far_ones_are_not(sphere):
    """frep-plate3 cut 12:0: a fill clamped into a convex corner landed 1.2e-16 from its input vertex;
    the scorer merges the two, so they are one group here too."""
    V, F = sphere
    n = len(V)
    V2 = np.vstack([V, V[3] + 1e-12, V[5] + 1e-3])
    F2 = np.vstack([F, [[n, 1, 2], [n + 1, 1, 2]]])
    assert not np.array_equal(V2[3], V2[n])
    assert [list(g) for g in coincident_groups(V2, F2)] == [[3, n]]


def test_close_clusters_are_the_components_of_the_pairs_within_the_radius():
    """Brute force: the clusters are the connected components of the graph of pairs at most the
    radius apart (the copies' groups, the darning's pinches and the benchmark's merge read them)."""
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial.distance import cdist

    from algorithms.copies import close_clusters

    rng = np.random.default_rng(3)
    P = rng.random((120, 3))
    P[60:80] = P[rng.integers(0, 60, 20)] + rng.normal(scale=1e-4, size=(20, 3))
    r = 3e-4
    _, want = connected_components(cdist(P, P) <= r, directed=False)
    got = close_clusters(P, r)
    assert len(np.unique(got)) == len(np.unique(want)) < 120
    assert np.array_equal(got[:, None] == got[None, :], want[:, None] == want[None, :])
    np.testing.assert_array_equal(close_clusters(P[:10], 1e-12), np.arange(10))


def test_pinch_joins_pair_copies_on_different_holes_once_each():
    from algorithms.bridge_graph import Bridge, Hole
    from algorithms.repair import _pinch_joins

    holes = [Hole((0, 1, 2, 3)), Hole((10, 11, 12)), Hole((20, 21, 22, 23, 24))]
    # input vertex 7: copies 1 and 11 (different holes), 8: copies 2 and 3 (one hole: the darning's),
    # 9: three copies 12, 21, 22 (12 pairs with 21; 22 is left), 5: copies 0 and 20, 0 a bridge end
    copies = {7: [11, 1], 8: [2, 3], 9: [22, 21, 12], 5: [0, 20]}
    taken = [Bridge(0, 30, np.zeros((1, 3)), 1.0)]
    got = _pinch_joins(holes, copies, taken)
    assert sorted((b.start, b.end) for b in got) == [(1, 11), (12, 21)]
    assert all(b.kind == "pinch" and len(b.points) == 0 for b in got)
    # on one hole too: 2 and 3 are paired, 21 and 22 (one hole) are the first pair of vertex 9
    got = _pinch_joins(holes, copies, taken, one_hole=True)
    assert sorted((b.start, b.end) for b in got) == [(1, 11), (2, 3), (12, 21)]
    copies[9] = [22, 21]
    assert sorted((b.start, b.end) for b in _pinch_joins(holes, copies, taken, one_hole=True)) == [
        (1, 11), (2, 3), (21, 22)]
    assert sorted((b.start, b.end) for b in _pinch_joins(holes, copies, taken)) == [(1, 11)]


def test_a_tunnel_past_a_pinch_is_one_from_a_joined_loop_to_a_loop_outside_its_group():
    from algorithms.bridge_graph import Bridge
    from algorithms.repair import _loop_groups, _past_a_pinch

    loop_of = {1: (0, 0), 2: (1, 0), 3: (1, 1), 4: (2, 0), 5: (3, 0), 6: (3, 1)}
    joins = [Bridge(1, 2, np.zeros((0, 3)), 0.0, "pinch"), Bridge(5, 6, np.zeros((0, 3)), 0.0, "pinch")]
    group = _loop_groups(joins, loop_of)  # loops 0 and 1 joined; 3 to itself (no group)
    assert set(group) == {0, 1} and group[0] == group[1]
    assert not _past_a_pinch((0, 1), group)  # a second band across the same handle
    assert _past_a_pinch((1, 2), group) and _past_a_pinch((0, 3), group)
    assert not _past_a_pinch((2, 3), group)


def test_a_wall_touching_the_floor_at_pinches_is_joined_there_not_by_a_tunnel(monkeypatch):
    """featuretype cut 3:1 (bench/sweep.py): a ball at the foot of a through-hole took the faces
    between the wall's slivers and the floor's rim, which then touch at 8 vertices; two more rows
    elsewhere. Darned apart and joined afterwards, 16 copies stayed apart (edges of four faces once
    merged by position), and the tunnel rule joined the wall's loop to the top's: genus 10 with the
    pinches joined, truth 9. The lines from the wall's loop to the top's cut across surface that is
    there (repair_field.surface_shortcuts), so the rule no longer proposes that tunnel; with the
    shortcut test off it does, and the pinch group refuses it (repair.PAST_A_PINCH). (Since one
    loop's winning lines may make a tunnel, repair_field.ONE_SIDED, the kept run joins the 8 copies
    at the wall's foot by pinch bridges and the rest into one vertex each; with that rule off, 16
    pinch bridges as before.)"""
    import algorithms.repair_field as rf
    from algorithms.repair import PAST_A_PINCH

    default = rf.SHORTCUT
    for one_sided, pinches in ((True, 8), (False, 16)):
        monkeypatch.setattr(rf, "ONE_SIDED", one_sided)
        for shortcut in (default, 0.0):
            monkeypatch.setattr(rf, "SHORTCUT", shortcut)
            res = sweep_repair("featuretype:3:1")
            assert_closed_once_merged(res, genus=9)
            assert res.copies_left == 0 and sum(b.kind == "pinch" for b in res.bridges) >= pinches
        assert any(why == PAST_A_PINCH for _, why in res.rejected)


@pytest.mark.parametrize("mode", ["light", "full"])
def test_copies_on_one_hole_that_a_crease_would_part_are_joined_first(mode):
    """featuretype cut 10:0 (bench/sweep.py): the part's edge x = -2.5, z = 0 (one input edge, 1.25
    long) is a border edge between copies of its ends, whose other copies lie on the same hole
    across the removed face. The crease continued from those other copies parted the hole between
    them before its darning could join them: 10 copies left apart (not closed once merged). Joined
    by pinch bridges on the hole first (the repair's third run), the crease from the copies is that
    edge: a chain with vertices along it made faces of 0 degrees once the copies merged."""
    from algorithms.metrics import min_angles

    res = sweep_repair("featuretype:10:0", mode)
    assert_closed_once_merged(res, genus=9)
    assert res.copies_left == 0 and sum(b.kind == "pinch" for b in res.bridges) >= 20
    assert "first run" in res.timings  # the kept run is a later one (the third: pinches on one hole)
    # the third: its pinch bridges are every pair on the holes, of which none lies on two holes
    assert sum(b.kind == "pinch" for b in res.bridges) == res.pinch_pairs_all > res.pinch_pairs == 0
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    assert min_angles(V, F[res.new_faces]).min() > 1.0
    P = res.model.mesh.vertices  # the bridges' ends are the model's vertices
    along = [b for b in res.bridges if b.kind == "crease" and np.allclose(P[[b.start, b.end]][:, [0, 2]], [-2.5, 0])]
    assert along and all(len(b.points) == 0 for b in along)


def test_a_patch_edge_is_flipped_where_that_folds_nothing_and_split_where_it_would():
    """copies._flip and copies._split on a quad of two patch faces, (u, w, x) and (w, u, y): the
    flip makes x - y the diagonal, the split puts m on u - w; both keep the faces' orientation."""
    from algorithms.copies import _flip, _split, _Star

    u, w, x, y = 0, 1, 2, 3
    quad = np.array([[u, w, x], [w, u, y]])
    flat = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0]])  # convex: the flip is fine
    star = _Star(quad)
    assert _flip(star, flat, u, w, 0)
    assert sorted(map(sorted, star.rows)) == [[0, 2, 3], [1, 2, 3]] and w not in star.neighbours(u)
    et = edge_table(np.array(star.rows))
    assert et.edges[et.counts == 2].tolist() == [[2, 3]]
    assert not _flip(_Star(quad), flat, u, w, 2)  # input faces are never flipped
    dart = flat.copy()
    dart[3] = [-0.5, -0.1, 0]  # the quad u y w x dented at u: the face u y x would be upside down
    assert not _flip(_Star(quad), dart, u, w, 0)
    star = _Star(quad)
    assert _split(star, u, w, 4, 0)
    F = np.array(star.rows)
    assert len(F) == 4 and w not in star.neighbours(u) and star.neighbours(4) == {u, w, x, y}
    et = edge_table(F)
    assert et.counts.max() == 2 and sorted(map(tuple, et.edges[et.counts == 2].tolist())) == \
        [(0, 4), (1, 4), (2, 4), (3, 4)]
    # orientation: every interior edge is walked once each way
    d = {(int(a), int(b)) for r in F for a, b in zip(r, np.roll(r, -1))}
    assert all((b, a) in d for a, b in d if 4 in (a, b))


def test_copies_with_a_neighbour_in_common_are_joined_after_parting_them(monkeypatch):
    """mushroom sweep cut 15:1 (light): the darning ran patch faces from each of two copies of a
    point on the stem's rim to a vertex of the other copy's input fan, so the two had two
    neighbours in common and no contraction could join them: two copies left apart, the output
    not closed once merged by position. Parted from those neighbours first (copies._unshared), the
    copies are joined and the output closes."""
    import algorithms.copies as copies

    monkeypatch.setattr(copies, "UNSHARE", False)
    res = sweep_repair("mushroom:15:1")
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    assert len(coincident_groups(V, F)) == 2 and "2 copies of a point left apart" in res.tunnel_note
    assert not topology(merge_positions(V, F, 1e-9)[1]).watertight
    monkeypatch.setattr(copies, "UNSHARE", True)
    res = sweep_repair("mushroom:15:1")
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    assert not coincident_groups(V, F) and "left apart" not in res.tunnel_note and res.copies_parted == 2
    topo = topology(merge_positions(V, F, 1e-9)[1])
    assert topo.watertight and topo.manifold_vertices and topo.components == 1
    assert_input_kept(res.model, res.mesh)

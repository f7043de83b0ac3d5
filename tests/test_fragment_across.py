"""A fragment left across a hole: three ball cuts of a torus leave one triangle whose corners touch
the hole's border at two vertices (its third vertex loose). Normalisation sets it aside; the repair
must put it back (every input face kept) by cutting the hole into the holes around it."""

from __future__ import annotations

import numpy as np
from test_repair import assert_input_kept

from algorithms.cases import cut, face_centroids, torus
from algorithms.fragments import _walk_around
from algorithms.metrics import topology
from algorithms.normalize import normalize
from algorithms.params import FieldParams
from algorithms.repair import RepairParams, repair


def _torus_case():
    t = torus(1.0, 0.4, 96, 36)
    c = face_centroids(t)
    remove = np.zeros(t.n_faces, dtype=bool)
    for v, r in ((42, 0.3654215224211993), (2417, 0.2677196516215011), (2446, 0.1807592697252886)):
        remove |= np.linalg.norm(c - t.vertices[v], axis=1) < r
    return cut(t, remove, name="torus, three balls", description="")


def test_walk_around_splits_a_square_hole():
    # a square hole 0-1-2-3 and a triangle fragment hanging at 0 and 2, its third vertex 9 towards 1
    # (loop 2 -> 9 -> 0): the holes left are 0-1-2-9 and the triangle 2-3-0 beyond its edge 0 -> 2
    assert _walk_around([(0, 1, 2, 3)], [2, 9, 0], {0, 2}) == [(0, 1, 2, 9), (2, 3, 0)]
    assert _walk_around([(0, 1, 2, 3)], [0, 9, 2], {0, 2}) == [(0, 1, 2), (2, 3, 0, 9)]  # 9 towards 3
    # a fragment edge 1 -> 0 against the hole edge 0 -> 1: the two become one inner edge, one hole left
    assert _walk_around([(0, 1, 2, 3)], [1, 0, 9], {0, 1}) == [(1, 2, 3, 0, 9)]
    # a fragment touching two holes (0-1-2 and 5-6-7) at 0 and 5 joins them into one walk through it
    assert _walk_around([(0, 1, 2), (5, 6, 7)], [0, 9, 5, 8], {0, 5}) == [(0, 1, 2, 0, 9, 5, 6, 7, 5, 8)]


def test_walk_around_a_vertex_passed_twice():
    # the hole 0-1-2-0-3-4 passes vertex 0 twice (a pinch); a triangle fragment 2 -> 9 -> 0 hangs at
    # 2 and 0. Joining the first pass of 0, it closes the gap 0-1-2 and the pinch stays in the rest;
    # joining the second, its edge 0 -> 2 meets the hole's edge 2 -> 0 (one inner edge) and one walk
    # is left, through both passes
    assert _walk_around([(0, 1, 2, 0, 3, 4)], [2, 9, 0], {0, 2}, {0: (0, 0), 2: (0, 2)}) == [
        (0, 1, 2, 9), (2, 0, 3, 4, 0)]
    assert _walk_around([(0, 1, 2, 0, 3, 4)], [2, 9, 0], {0, 2}, {0: (0, 3), 2: (0, 2)}) == [
        (0, 1, 2, 9, 0, 3, 4)]


def test_fragment_touching_two_border_vertices_is_kept():
    case = _torus_case()
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    fragments = [s for s in model.set_aside if s.reason.startswith("fragment")]
    assert len(fragments) == 1
    for mode in ("light", "full"):  # one loose vertex: a single free point (full mode crashed on it)
        res = repair(model, RepairParams(field=FieldParams(mode=mode)))
        t = topology(res.mesh.faces)
        assert t.watertight and t.components == 1 and t.genus == 1
        assert res.attached is not None and res.attached.input_faces == (fragments[0].face,)
        assert_input_kept(model, res.mesh)
        # the input face itself, not only its vertices: its three corners form a face of the output
        keys = {tuple(sorted(map(tuple, np.round(res.mesh.vertices[f], 9)))) for f in res.mesh.faces}
        tri = case.incomplete.vertices[list(fragments[0].vertices)] if max(fragments[0].vertices) < len(
            case.incomplete.vertices) else None
        assert tri is not None and tuple(sorted(map(tuple, np.round(tri, 9)))) in keys


def test_the_walk_is_not_cut_around_a_fragment_at_the_end_of_a_chain():
    """fragments._pinch: a walk that passes vertex 5 twice, the side between the passes being one
    fragment's loop alone (5, 6, 7: a fragment hanging at another), is not cut there; the same
    walk is cut where a chain of fragments crosses it (both sides hold other vertices)."""
    from algorithms.fragments import _pinch

    walk = (0, 1, 5, 6, 7, 5, 2, 3)
    marks = {5: None, 6: None, 7: None}
    assert _pinch(walk, marks, [{5, 6, 7}]) is None
    assert _pinch(walk, marks) == (2, 5)  # without the fragments' vertex sets: cut (the old rule)
    across = (0, 1, 5, 6, 2, 3, 5, 7)  # each side holds border vertices: a chain across the hole
    assert _pinch(across, marks, [{5, 6, 7}]) == (2, 6)


def test_a_fragment_across_a_hole_is_a_join_the_guard_counts():
    """The torus's fragment hangs at two vertices of one loop (its third is loose): one stand-in
    join between exactly those two loop vertices (repair._fragment_joins), which the topology guard
    counts as splitting that loop's walk, not as a handle."""
    from algorithms.boundary import summarize
    from algorithms.bridge_graph import TopologyGuard
    from algorithms.fragments import hanging_points
    from algorithms.repair import _fragment_joins

    cut_torus = _torus_case().incomplete
    model = normalize(cut_torus.vertices, cut_torus.faces)
    face = next(s for s in model.set_aside if s.reason.startswith("fragment"))
    frames = summarize(model).loops
    loops = [f.vertices for f in frames]
    on_loops = {int(v) for lp in loops for v in lp}
    (points,) = hanging_points(model)
    assert sorted(points) == sorted(v for v in face.vertices if v in on_loops) and len(points) == 2
    copies = {int(model.vertex_origin[v]): [v] for v in on_loops}
    guard = TopologyGuard(loops, [f.island for f in frames])
    (b,) = _fragment_joins([points], copies, guard.island_of)
    assert {b.start, b.end} == set(points) and len(b.points) == 0
    assert guard.effect(b.start, b.end) == "split"
    # a point with two copies on the loops is left out: no join from one point
    assert _fragment_joins([points], {points[0]: [points[0], 10**6], points[1]: [points[1]]}, guard.island_of) == []


def test_a_fragment_at_three_points_is_one_join_per_point_across_islands_first():
    """The walking rule takes one bridge per vertex: a fragment hanging at points 1, 2 (island 0)
    and 3 (island 1) is one stand-in across the islands (the first such pair, 1-3), never a chain
    1-2, 2-3 through the middle point; at two points of one island, one stand-in; at four points on
    two islands, two stand-ins across them that share no point."""
    from algorithms.repair import _fragment_joins

    island = {1: 0, 2: 0, 3: 1, 4: 1, 5: 2}
    copies = {v: [v] for v in island}
    ends = lambda hanging: [(b.start, b.end) for b in _fragment_joins(hanging, copies, island)]  # noqa: E731
    assert ends([[1, 2, 3]]) == [(1, 3)]
    assert ends([[1, 2]]) == [(1, 2)]
    assert ends([[1, 2, 3, 4]]) == [(1, 3), (2, 4)]
    assert ends([[1, 2], [3, 5]]) == [(1, 2), (3, 5)]  # each fragment on its own


def test_a_fragment_between_two_islands_joins_them_before_the_bridges(monkeypatch):
    """bench/sweep.py cut trefoil+cross:1:0 (two slabs through the knot): input face 6860 is left
    hanging at a corner of each of two islands (vertices 2910 and 2911). Walked in after the island
    bridges, it joined them a third time beside two island bridges (one ending at its corner 2910),
    and the walk around the three passed two bridges in crossed order: a second handle (genus 2,
    truth 1). Counted as their join before the bridges (repair.FRAGMENT_JOINS), genus 1."""
    import algorithms.repair as rp
    from bench.sweep import make_cut

    case = make_cut("trefoil", 1, 0, "cross")
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    assert any(s.face == 6860 and set(s.vertices) >= {2910, 2911} for s in model.set_aside)
    for mode in ("light", "full"):
        res = repair(model, RepairParams(field=FieldParams(mode=mode)))
        t = topology(res.mesh.faces)
        assert t.watertight and t.components == 1 and t.genus == 1
        assert 6860 in res.attached.input_faces
        assert_input_kept(model, res.mesh, fragments=True)
        assert not any({b.start, b.end} & {2910, 2911} for b in res.bridges if b.kind == "island")
    monkeypatch.setattr(rp, "FRAGMENT_JOINS", False)
    assert topology(repair(model, RepairParams()).mesh.faces).genus == 2

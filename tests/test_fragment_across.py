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

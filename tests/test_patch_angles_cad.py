"""Patch angles beside the crease chains of a CAD part (featuretype.stl, shared data): a crease chain
leaving a border vertex at a narrow angle to a long border edge keeps its first vertex far enough
out that the one face the wedge holds is not a sliver (creases.end_clearance)."""

import numpy as np
import pytest
from conftest import data_file
from scipy.spatial import cKDTree

from algorithms import cases as gen
from algorithms.io import load_raw
from algorithms.mesh import Mesh
from algorithms.metrics import triangle_angles
from algorithms.normalize import normalize
from algorithms.repair import repair
from algorithms.topology import edge_table


def _featuretype_hole():
    """bench.cases' featuretype-hole: a hole across the top face and a side of featuretype.stl."""
    from bench.cases import ball, surface_point

    v, f = load_raw(data_file("featuretype.stl"))
    ft = Mesh(v, f)
    d = ft.bbox_diagonal()
    fh = ball(ft, surface_point(ft, [0.1, 0.2, 1]), 0.12 * d) | ball(ft, surface_point(ft, [1, 0.3, 0.2]), 0.108 * d)
    return gen.cut(ft, fh, name="featuretype-hole", description="").incomplete


@pytest.fixture(scope="module")
def repaired():
    cut = _featuretype_hole()
    return cut, repair(normalize(cut.vertices, cut.faces))


def test_crease_chain_ends_leave_no_sliver_on_a_long_border_edge(repaired):
    cut, res = repaired
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    patch = F[res.new_faces]
    et = edge_table(np.asarray(cut.faces))
    border = {tuple(e) for e in np.sort(et.edges[et.counts == 1], axis=1)}
    to_out = cKDTree(V)
    # the input's vertex numbers in the output (every input face is kept, at the same positions)
    _, idx = to_out.query(np.asarray(cut.vertices))
    back = {int(o): i for i, o in enumerate(idx)}
    creases = [b for b in res.bridges if b.kind == "crease" and len(b.points)]
    assert creases
    wedges = 0
    for b in creases:
        poly = b.polyline(V)
        _, ids = to_out.query(np.vstack([poly[:2], poly[-2:][::-1]]))
        for e, c in (ids[:2], ids[2:]):
            for face in patch[(patch == e).any(axis=1) & (patch == c).any(axis=1)]:
                w = int(next(x for x in face if x not in (e, c)))
                if w not in back or int(e) not in back:
                    continue
                if tuple(sorted((back[int(e)], back[w]))) not in border:
                    continue  # the wedge's other edge is a patch edge: it could be split
                ang = triangle_angles(V, face[None])[0]
                at = {int(x): a for x, a in zip(face, ang)}
                if at[int(e)] < 44.0:  # a wedge with room for one face: its far corner keeps 20 deg
                    wedges += 1
                    assert at[w] >= 20.0, (at, face)
    assert wedges >= 2  # the chain along the top face's edge: the top face's and the side's wedge


def test_split_chains_beside_creases_do_not_hug_an_input_edge(repaired):
    """The crease-aware fairing moves the split chains beside a crease patch off their force lines;
    the angle refinement may then move them too: no new vertex ends up over an edge between two input
    vertices (before: a chain vertex 0.025 from a 0.23 chord 805-886, 151.8 deg at it, 14.1 deg at both
    of the edge's ends, the chain vertex held fixed by the refinement)."""
    cut, res = repaired
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    patch = F[res.new_faces]
    _, idx = cKDTree(V).query(np.asarray(cut.vertices))
    inputs = set(idx.tolist())
    new = np.setdiff1d(np.arange(len(V)), idx)  # chain and patch vertices (the chains moved: not found by position)
    checked = 0
    for face in patch:
        ang = triangle_angles(V, face[None])[0]
        for k in range(3):
            a, b, c = int(face[k]), int(face[(k + 1) % 3]), int(face[(k + 2) % 3])
            if a in new and b in inputs and c in inputs:  # a border edge or a chord between two of them
                checked += 1
                # hugging: both angles at the edge's ends small (the bug: 14.1 and 14.1). Not hugging: a face over
                # the 0.41 border edge 248-245 with 17.5 at both ends (145.1 at the new vertex: refine._polish's
                # graded fan, one face below 20 deg being forced at 248), or a crease corner (14.3 and 26.1)
                assert max(ang[(k + 1) % 3], ang[(k + 2) % 3]) >= 15.0, (face, ang)
    assert checked >= 3


def test_unforced_slivers_on_featuretype(repaired):
    """featuretype-hole's patch: unforced angles (not between two input border edges) of at least 14
    deg, at most one face below 15 deg (14.3, between a border edge and a continued crease: the input
    border edge leaves the crease's end at that angle), and at most 7 % of the patch's faces below 20
    deg unforced (measured 9 of 146, 6.2 %; the issue's target is 5 %). Before refine._polish: 13.2 deg
    twice, beside a 0.41 border edge next to the 0.04 chords of a boss rim, and 14 faces (10.4 %)
    below 20 deg."""
    from algorithms.metrics import forced_faces, min_angles

    cut, res = repaired
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    patch = F[res.new_faces]
    _, idx = cKDTree(V).query(np.asarray(cut.vertices))
    et = edge_table(np.asarray(cut.faces))
    forced = forced_faces(V, patch, idx[et.edges[et.counts == 1]])
    ang = min_angles(V, patch)[~forced]
    assert ang.min() >= 14.0
    assert (ang < 15.0).sum() <= 1
    assert (ang < 20.0).sum() <= 0.07 * len(patch)


def test_flat_stars():
    from algorithms.repair import _flat_stars

    # a fan of 6 faces around vertex 0 in the plane z = 0, then the same fan with one rim vertex lifted
    a = np.linspace(0, 2 * np.pi, 7)[:-1]
    V = np.vstack([[0.0, 0.0, 0.0], np.c_[np.cos(a), np.sin(a), np.zeros(6)]])
    F = np.array([[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)])
    assert _flat_stars(V, F, np.array([0]), 1.5).tolist() == [0]
    V2 = V.copy()
    V2[3, 2] = 0.1  # its two faces turn by ~5.7 degrees
    assert _flat_stars(V2, F, np.array([0]), 1.5).tolist() == []
    assert _flat_stars(V2, F, np.array([0]), 10.0).tolist() == [0]

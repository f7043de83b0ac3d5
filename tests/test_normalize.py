
import numpy as np
import pytest
from conftest import data_file

from algorithms.boundary import summarize
from algorithms.cases import disk
from algorithms.io import load_model
from algorithms.mesh import MeshError
from algorithms.normalize import normalize
from algorithms.topology import edge_table, orientation_consistent


def square():
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    return v, f


def test_clean_input_is_untouched():
    v, f = square()
    m = normalize(v, f)
    assert m.set_aside == ()
    np.testing.assert_array_equal(m.mesh.faces, f)
    assert not m.flipped.any()


def test_duplicate_with_opposite_orientation_is_set_aside():
    v, f = square()
    f2 = np.vstack([f, [[2, 1, 0]]])  # face 0 again, reversed
    m = normalize(v, f2)
    assert len(m.set_aside) == 1
    sa = m.set_aside[0]
    assert sa.face == 4 and "duplicate of face 0" in sa.reason and "opposite" in sa.reason
    assert m.mesh.n_faces == 4 and orientation_consistent(m.mesh.faces)


def test_degenerate_faces_reported():
    v, f = square()
    v = np.vstack([v, [[3, 0, 0]]])
    f2 = np.vstack([f, [[0, 0, 1]], [[1, 4, 6]]])  # repeated vertex; collinear points
    m = normalize(v, f2)
    reasons = {s.face: s.reason for s in m.set_aside}
    assert "repeated" in reasons[4] and "zero area" in reasons[5]
    # vertex 6 belongs only to a set-aside face: it becomes a free point, nothing is lost
    assert any(np.allclose(p, [3, 0, 0]) for p in m.free_points)


def test_inconsistent_orientation_is_fixed_minority_flipped():
    v, f = square()
    f2 = f.copy()
    f2[3] = f2[3][::-1]
    m = normalize(v, f2)
    assert m.set_aside == ()
    assert orientation_consistent(m.mesh.faces)
    assert m.flipped.sum() == 1 and m.flipped[3]


def test_nonmanifold_edge_fin_keeps_every_face():
    # a fin: a third face on edge (1, 2) standing up out of the plane
    v, f = square()
    v = np.vstack([v, [[1, 0.5, 1]]])
    f2 = np.vstack([f, [[1, 2, 6]]])
    m = normalize(v, f2)
    # the two flat faces continue each other; the fin is cut off along the edge, kept as its
    # own island (it touches the sheet along an edge, so it is not a vertex-only fragment
    # after the split: the edge vertices were copied)
    assert np.all(edge_table(m.mesh.faces).counts <= 2)
    total = m.mesh.n_faces + len(m.set_aside)
    assert total == 5


def test_bowtie_vertex_is_split():
    # two fans meeting at vertex 0
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0], [-1, -1, 0], [0, 1, 0], [0, -1, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 5], [0, 3, 4], [0, 4, 6]])
    m = normalize(v, f, tiny_fragment=0)
    assert m.set_aside == ()
    assert m.mesh.n_vertices == 8 and m.vertex_origin[7] == 0
    s = summarize(m)
    assert len(s.islands) == 2


def test_tiny_fragment_at_vertex_is_set_aside():
    big = disk(segments=16, rings=2)
    v = np.vstack([big.vertices, [[2, 0, 0.5], [2, 0.3, 0.5]]])
    # a single triangle hanging off boundary vertex 17 (at (1,0,0)) of the disk
    f = np.vstack([big.faces, [[17, len(big.vertices), len(big.vertices) + 1]]])
    m = normalize(v, f)
    assert len(m.set_aside) == 1 and "fragment of 1 faces" in m.set_aside[0].reason
    assert len(m.free_points) == 2  # its two own vertices become free points


def test_nan_is_rejected():
    v, f = square()
    v[2, 1] = np.nan
    with pytest.raises(MeshError, match="vertex 2"):
        normalize(v, f)


def test_real_bunny():
    m = load_model(data_file("bunny.ply"))
    s = summarize(m)
    assert len(s.islands) == 1
    assert len(s.loops) == 5
    assert sorted(len(lp.vertices) for lp in s.loops) == [11, 22, 28, 28, 38]
    assert m.free_point_counts()["unreferenced"] == 25
    dup = [x for x in m.set_aside if x.reason.startswith("duplicate")]
    assert 80 <= len(dup) <= 100
    assert all(x.reason for x in m.set_aside)
    assert np.all(edge_table(m.mesh.faces).counts <= 2)
    assert orientation_consistent(m.mesh.faces)
    # nothing disappears: kept + set aside = input
    assert m.mesh.n_faces + len(m.set_aside) == 16301

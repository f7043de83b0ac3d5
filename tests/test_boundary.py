import numpy as np
import pytest

from algorithms.boundary import loop_frames, summarize
from algorithms.cases import combine, disk, icosphere, torus
from algorithms.mesh import Icadm


def frame_at(frames, point):
    for fr in frames:
        d = np.linalg.norm(fr.points - np.asarray(point), axis=1)
        k = int(np.argmin(d))
        if d[k] < 1e-9:
            return fr, k
    raise AssertionError("point not on a boundary")


def test_unit_disk_worked_example():
    # spec/repair.md §2: at O = (1,0,0) tau = (0,1,0), n = (0,0,1), b = (1,0,0)
    frames = loop_frames(disk(segments=64))
    assert len(frames) == 1
    fr, k = frame_at(frames, (1, 0, 0))
    np.testing.assert_allclose(fr.tangent[k], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(fr.normal[k], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(fr.outward[k], [1, 0, 0], atol=1e-12)
    # charge: half the sum of the two boundary edges = the chord 2 sin(pi/64)
    assert fr.charge[k] == pytest.approx(2 * np.sin(np.pi / 64))
    assert fr.charge.sum() == pytest.approx(fr.length)
    # every outward direction points away from the centre
    assert np.all(np.einsum("ij,ij->i", fr.outward, fr.points) > 0.99)


def test_flipped_disk_reverses_tangent_keeps_outward():
    fr, k = frame_at(loop_frames(disk(flip=True)), (1, 0, 0))
    np.testing.assert_allclose(fr.tangent[k], [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(fr.normal[k], [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(fr.outward[k], [1, 0, 0], atol=1e-12)


def test_unit_charge_rule():
    fr = loop_frames(disk(), charge="unit")[0]
    assert np.all(fr.charge == 1)
    with pytest.raises(ValueError, match="charge"):
        loop_frames(disk(), charge="banana")


def test_summary_two_disks_is_icm3():
    m = combine(disk(), disk(center=(4, 0, 0)))
    s = summarize(Icadm(m))
    assert s.class_guess == "ICM3"
    assert [i.euler for i in s.islands] == [1, 1]
    assert [i.genus for i in s.islands] == [0, 0]
    assert {lp.island for lp in s.loops} == {0, 1}


def test_closed_sphere_and_torus_genus():
    s = summarize(Icadm(icosphere(2)))
    assert s.class_guess == "closed" and s.islands[0].euler == 2 and s.islands[0].genus == 0
    t = summarize(Icadm(torus()))
    assert t.islands[0].euler == 0 and t.islands[0].genus == 1


def test_simple_loop_walk_equals_the_general_walk():
    """boundary_loops' successor walk (every boundary vertex on one loop once) gives the loops of
    the general fan walk, same start vertices, same order, on cut demo shapes with many holes."""
    from algorithms import cases
    from algorithms.topology import _simple_loops, _walk_loops, boundary_halfedges

    rng = np.random.default_rng(2)
    for mesh in (cases.icosphere(4), cases.torus()):
        c = cases.face_centroids(mesh)
        d = mesh.bbox_diagonal()
        holes = np.zeros(len(c), dtype=bool)
        for vi in rng.choice(mesh.n_vertices, 12, replace=False):
            holes |= np.linalg.norm(c - mesh.vertices[vi], axis=1) < 0.05 * d
        f = np.asarray(mesh.faces)[~holes]
        bhe = boundary_halfedges(f)
        nv = int(f.max()) + 1
        fast, walk = _simple_loops(bhe, nv), _walk_loops(f, bhe, nv)
        assert len(walk) > 3
        assert len(fast) == len(walk) and all(np.array_equal(a, b) for a, b in zip(fast, walk))


def test_face_adjacency_with_its_shared_edges():
    """Two triangles on edge (1, 2) and a third face on it too (a non-manifold edge): the pairs and,
    with ``with_edges``, the edge each pair shares."""
    from algorithms.topology import face_adjacency

    f = np.array([[0, 1, 2], [2, 1, 3], [1, 2, 4], [2, 3, 5]])
    pairs, edges = face_adjacency(f, manifold_only=False, with_edges=True)
    got = sorted((tuple(sorted(p)), tuple(e)) for p, e in zip(pairs.tolist(), edges.tolist()))
    assert got == [((0, 1), (1, 2)), ((1, 2), (1, 2)), ((1, 3), (2, 3))]
    pairs, edges = face_adjacency(f, with_edges=True)  # the manifold edges only
    assert pairs.tolist() == [[1, 3]] and edges.tolist() == [[2, 3]]
    plain = face_adjacency(f, manifold_only=False)
    assert np.array_equal(plain, face_adjacency(f, manifold_only=False, with_edges=True)[0])

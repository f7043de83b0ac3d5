import numpy as np
import pytest

from algorithms.cases import cap, icosphere, torus
from algorithms.metrics import (
    angle_histogram,
    angle_stats,
    distances,
    edge_length_cv,
    min_angles,
    normal_deviation,
    surface_area,
    topology,
    triangle_angles,
)


def test_equilateral_angles():
    v = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
    np.testing.assert_allclose(triangle_angles(v, [[0, 1, 2]]), [[60, 60, 60]])


def test_right_isoceles_angles_and_stats():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_allclose(triangle_angles(v, [[0, 1, 2]]), [[90, 45, 45]])
    s = angle_stats(np.array([10.0, 25.0, 45.0, 60.0]))
    assert s.min == 10 and s.below_20 == 0.25 and s.below_30 == 0.5 and s.median == 35
    edges, counts = angle_histogram(np.array([1.0, 59.0, 60.0]), bin_width=10)
    assert len(edges) == 7 and counts.tolist() == [1, 0, 0, 0, 0, 2]


def test_sphere_area_converges():
    s = icosphere(5)
    assert surface_area(s.vertices, s.faces) == pytest.approx(4 * np.pi, rel=2e-3)


def test_topology_summaries():
    t = topology(torus().faces)
    assert t.watertight and t.components == 1 and t.euler == 0 and t.genus == 1
    s = icosphere(2)
    o = topology(s.faces[~cap(s, [0, 0, 1], 30)])
    assert not o.watertight and o.boundary_loops == 1 and o.components == 1 and o.genus == 0 and o.euler == 1
    assert t.manifold_vertices and o.manifold_vertices


def test_two_closed_surfaces_pinched_at_a_vertex_are_not_manifold_there():
    """Two spheres glued at one vertex: every edge has two faces, and each closed fan has as many
    links as faces, so only the fans themselves tell the pinch (vertex_fans)."""
    from algorithms.topology import nonmanifold_vertices, vertex_fans

    s = icosphere(1)
    f2 = s.faces + s.n_vertices
    f2[f2 == s.n_vertices] = 0  # the second sphere's vertex 0 is the first's
    faces = np.vstack([s.faces, f2])
    t = topology(faces)
    assert t.watertight and t.manifold_edges and not t.manifold_vertices
    assert nonmanifold_vertices(faces).tolist() == [0]
    fans = vertex_fans(faces)[0]
    assert sorted(len(f) for f in fans) == [5, 5]  # an icosphere vertex of valence 5, twice
    assert set(fans[0]) | set(fans[1]) == set(np.flatnonzero((faces == 0).any(axis=1)).tolist())


def test_distance_to_unit_offset_surface():
    # a sphere of radius 2 against one of radius 1: every point is ~1 away
    a, b = icosphere(4, radius=1.0), icosphere(4, radius=2.0)
    d = distances(b.vertices, b.faces, a.vertices, a.faces, samples=3000)
    diag = np.linalg.norm(a.vertices.max(0) - a.vertices.min(0))
    assert d.hausdorff * diag == pytest.approx(1.0, abs=0.01)
    assert d.mean * diag == pytest.approx(1.0, abs=0.01)


def test_normal_deviation_and_uniformity():
    n = np.array([[0, 0, 1.0], [1, 0, 0]])
    np.testing.assert_allclose(normal_deviation(n, [[0, 0, 1], [0, 1, 0]]), [0, 90], atol=1e-9)
    s = icosphere(3)
    assert edge_length_cv(s.vertices, s.faces) < 0.15
    assert min_angles(s.vertices, s.faces).min() > 45


def test_vertex_faces_lists_the_faces_at_each_vertex():
    """topology.VertexFaces (the table the repair's neighbourhoods and the refinement's collapses
    read) against a scan of every face, on random faces with repeated and unused vertices."""
    from algorithms.topology import VertexFaces

    rng = np.random.default_rng(5)
    f = rng.integers(0, 30, size=(80, 3))
    f[3] = (7, 7, 9)  # a vertex twice in one face: listed once by rows()
    table = VertexFaces(f, 35)
    for v in range(35):
        assert table.rows(v).tolist() == np.flatnonzero((f == v).any(axis=1)).tolist()
    assert table.start[-1] == f.size and table.rows(34).size == 0


def test_edge_table_of_a_large_array_is_kept_read_only_and_keyed_by_contents():
    """topology.edge_table keeps the tables of the last large face arrays: a copy of the same faces
    gets the same table, a changed array its own; the kept arrays cannot be written; small arrays
    are tabled every time."""
    from algorithms.topology import _EDGE_CACHE_MIN, _edge_table, edge_table

    s = icosphere(5)  # 20,480 faces
    f = np.asarray(s.faces, dtype=np.int64)
    assert len(f) >= _EDGE_CACHE_MIN
    et = edge_table(f)
    assert edge_table(f.copy()) is et
    ref = _edge_table(f)
    for a, b in zip((et.edges, et.halfedge_edge, et.counts), (ref.edges, ref.halfedge_edge, ref.counts)):
        np.testing.assert_array_equal(a, b)
        assert not a.flags.writeable
    g = f.copy()
    g[0] = g[0, ::-1]
    assert edge_table(g) is not et
    small = f[:100]
    assert edge_table(small) is not edge_table(small) and edge_table(small).counts.flags.writeable

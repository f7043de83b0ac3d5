"""Sampling, linking, holes and the whole F-rep pipeline on analytic objects."""

import numpy as np
import pytest

from algorithms.frep.linking import link, section_successors
from algorithms.frep.objects import blobs, demo_object, perturbed, sphere, torus
from algorithms.frep.pipeline import FrepParams, triangulate_object
from algorithms.frep.sampling import BOTTOM, TOP, sample
from algorithms.metrics import topology
from algorithms.topology import boundary_loops


def test_sampling_finds_all_crossings_of_a_sphere():
    obj = sphere(0.8)
    s = sample(obj, qlev=5, blev=14)
    # every column through the disk x^2 + y^2 < r^2 has exactly two crossings at +-sqrt(r^2 - rho^2)
    x, y, z = s.points.T
    rho2 = x**2 + y**2
    assert np.allclose(np.abs(z), np.sqrt(0.64 - rho2), atol=2 / 2**14)
    n = 2**5
    c = -1 + 2 * (np.arange(n) + 0.5) / n
    X, Y = np.meshgrid(c, c, indexing="ij")
    assert len(s.points) == 2 * int((X**2 + Y**2 < 0.64).sum())
    assert np.all(s.point_kind[z < 0] == BOTTOM) and np.all(s.point_kind[z > 0] == TOP)


def test_all_intersections_of_a_ray_are_kept():
    # a torus seen along its axis: columns through the tube's hole ring have 2 crossings,
    # a vertical torus (axis x) has columns with 4 crossings
    obj = demo_object("torus")
    from algorithms.frep.objects import from_expression

    vt = from_expression("0.25**2 - (sqrt(y**2 + z**2) - 0.6)**2 - x**2", name="vtorus")
    s = sample(vt, qlev=5, blev=12)
    counts = np.bincount(np.ravel_multi_index(s.point_col.T, (32, 32)))
    assert counts.max() == 4
    assert np.abs(vt.value(s.points)).max() < 1e-5
    assert len(sample(obj, qlev=5, blev=12).points) > 0


@pytest.mark.parametrize("obj", [sphere(), torus(), perturbed()], ids=["sphere", "torus", "perturbed"])
def test_section_successors_are_permutations(obj):
    s = sample(obj, qlev=5, blev=10)
    for axis in (0, 1):
        succ = section_successors(s, axis=axis)
        assert np.array_equal(np.sort(succ), np.arange(len(s.points)))
        # a step along a section moves at most one column (or turns round within one)
        d = np.abs(s.point_col[succ] - s.point_col)
        assert np.all(d[:, axis] == 0) and np.all(d[:, 1 - axis] <= 1)


def test_linking_a_sphere_gives_one_oriented_surface_with_small_holes():
    obj = sphere()
    s = sample(obj, qlev=5, blev=12)
    L = link(s, obj)
    t = topology(L.faces)
    assert t.manifold_edges and t.oriented and t.components == 1
    loops = boundary_loops(L.faces)
    assert 0 < len(loops) and max(len(lp) for lp in loops) < 40
    # outward orientation: positive signed volume
    p = s.points[L.faces]
    vol = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6
    assert vol > 0
    # the top cap is a regular grid of quads: 2 triangles per cell seen from above
    assert len(L.quads) > 0.9 * len(s.points)


@pytest.mark.parametrize("name, genus", [("sphere", 0), ("torus", 1), ("blob", 0), ("perturbed", 0),
                                         ("boxsphere", 0)])
def test_closed_objects_come_out_watertight_with_the_right_genus(name, genus):
    r = triangulate_object(demo_object(name), qlev=5)
    t = r.metrics.topology
    assert t.watertight and t.components == 1 and t.boundary_loops == 0
    assert t.genus == genus
    assert len(r.loops) > 0  # there were holes, and they were filled
    p = np.asarray(r.mesh.vertices)[np.asarray(r.mesh.faces)]
    assert np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() > 0  # outward
    # the result keeps every linked quad face
    q = {tuple(sorted(f)) for f in np.asarray(r.quad_mesh.faces).tolist()}
    out = {tuple(sorted(f)) for f in np.asarray(r.faired.faces).tolist()}
    assert len(q - out) <= int(r.region.sum())


def test_liepa_filling_closes_every_hole_and_stages_are_recorded():
    r = triangulate_object(torus(), FrepParams(qlev=5))
    assert topology(np.asarray(r.quad_mesh.faces)).boundary_loops == len(r.loops) > 0
    assert topology(np.asarray(r.filled.faces)).watertight  # after Liepa alone
    assert r.filled_patch.sum() == sum(len(lp) - 2 for lp in r.loops)  # a disk of n-gon: n - 2 triangles
    assert r.region.sum() >= r.filled_patch.sum()
    assert r.refined_new.sum() == len(r.faired.vertices) - len(r.filled.vertices)
    stages = r.stages()
    assert [st.name for st in stages] == ["points", "quads", "holes", "filled", "region", "refined", "faired"]
    for st in stages:
        assert st.highlight is None or len(st.highlight) == len(st.faces)
        assert not len(st.faces) or st.faces.max() < len(st.vertices)
    assert len(stages[2].loops) == len(r.loops)
    assert stages[-1].highlight.sum() == len(r.faired.faces) - int((~r.region).sum())
    rep = r.report()
    assert rep["holes"] == len(r.loops) and rep["metrics"]["topology"]["genus"] == 1


def test_metrics_on_a_sphere_are_small_and_consistent():
    r = triangulate_object(sphere(0.8), qlev=6)
    m = r.metrics
    voxel = 2 / 64
    assert m.voxel == pytest.approx(voxel)
    # sample points lie on the surface to the linear-interpolation precision; new vertices near it
    assert m.deviation_mean < 0.02 * voxel and m.deviation_max < 0.5 * voxel
    assert m.projected_max == pytest.approx(m.deviation_max, rel=0.05)  # first order ~ exact for a sphere
    # the true sphere distance agrees
    d = np.abs(np.linalg.norm(r.mesh.vertices, axis=1) - 0.8)
    assert d.max() == pytest.approx(m.projected_max, rel=1e-3, abs=1e-9)
    assert m.face_normal_mean < 3 and m.vertex_normal_mean < 1.5
    assert sum(m.histogram_counts) == m.faces
    assert 0 < m.edge_cv < 1


def test_projection_moves_new_vertices_onto_the_surface():
    a = triangulate_object(blobs(), qlev=5, project=False, smooth=0)
    b = triangulate_object(blobs(), qlev=5, smooth=0)
    assert b.metrics.deviation_max < 1e-6 < a.metrics.deviation_max


def test_params_are_validated():
    for bad in ({"qlev": 0}, {"blev": 40}, {"diagonal": "BD"}, {"weight": "volume"}, {"fairing": "U3"},
                {"side_slope": 2.0}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            FrepParams(**bad)


@pytest.mark.parametrize("name, genus", [("sphere", 0), ("torus", 1)])
def test_paper_literal_settings_are_watertight_too(name, genus):
    # ABC/ACD split, only zero-projected-area side faces merged, no projection
    r = triangulate_object(demo_object(name), qlev=5, diagonal="AC", side_slope=1e-6, project=False)
    t = r.metrics.topology
    assert t.watertight and t.genus == genus


def test_quality_targets_on_a_sphere():
    m = triangulate_object(sphere(0.8), qlev=6).metrics
    assert m.angles.below_20 < 0.02  # issue target: under 2 % of angles below 20 degrees
    assert m.edge_cv < 0.3 and m.face_normal_mean < 1.0
    assert m.projected_max < 0.5 * m.voxel


@pytest.mark.parametrize("name, genus", [("torus", 1), ("boxsphere", 0), ("perturbed", 0)])
def test_isotropic_improvement_keeps_the_surface_and_evens_edges(name, genus):
    a = triangulate_object(demo_object(name), qlev=6, smooth=0)  # the paper's pipeline
    b = triangulate_object(demo_object(name), qlev=6)  # default: + valence flips and CVT relaxation
    assert b.metrics.topology.watertight and b.metrics.topology.genus == genus
    assert b.metrics.topology.euler == a.metrics.topology.euler
    assert len(b.mesh.vertices) == len(a.mesh.vertices) and len(b.mesh.faces) == len(a.mesh.faces)
    assert b.metrics.projected_max < 1e-6  # every vertex back on F = 0 (R-function creases: ~1e-8)
    assert b.metrics.edge_cv < a.metrics.edge_cv and b.metrics.edge_cv <= 0.2  # issue 7 target
    assert b.metrics.angles.min > a.metrics.angles.min and b.metrics.angles.below_20 == 0
    assert b.improve_flips > 0


def test_valence_flips_bring_valences_towards_six_and_keep_orientation():
    from algorithms.frep.remesh import valence_flips
    from algorithms.topology import edge_table

    r = triangulate_object(sphere(0.8), qlev=5, smooth=0)
    V, F = np.asarray(r.mesh.vertices), np.asarray(r.mesh.faces)
    F2, k = valence_flips(V, F)
    assert k > 0 and F2.shape == F.shape

    def deviation(faces):
        val = np.bincount(edge_table(faces).edges.ravel(), minlength=len(V))
        return int(((val - 6) ** 2).sum())

    assert deviation(F2) < deviation(F)
    et = edge_table(F2)
    assert (et.counts == 2).all()  # still closed and manifold
    # consistently oriented: every undirected edge is used once in each direction
    he = np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]])
    assert len({tuple(e) for e in he.tolist()}) == len(he)
    # outward normals (the sphere is centred at the origin)
    n = np.cross(V[F2[:, 1]] - V[F2[:, 0]], V[F2[:, 2]] - V[F2[:, 0]])
    assert (np.einsum("ij,ij->i", n, V[F2].mean(axis=1)) > 0).all()


@pytest.mark.parametrize("name, volume", [("sphere", 4 / 3 * np.pi * 0.8**3), ("torus", 2 * np.pi**2 * 0.6 * 0.25**2)])
def test_enclosed_volume_matches_the_analytic_one(name, volume):
    r = triangulate_object(demo_object(name), qlev=6)
    p = np.asarray(r.mesh.vertices)[np.asarray(r.mesh.faces)]
    vol = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6
    assert vol == pytest.approx(volume, rel=0.01)


def test_genus_two_block_with_vertical_tubes():
    # an R-function object with two through holes along the rays: their walls are side faces
    # (zero projected area) merged into the refined region; fairing alone would pull the tube
    # walls in, the result must still hug F = 0 with good triangles
    from algorithms.frep.objects import from_expression

    obj = from_expression("r_and(0.81 - x**2 - 2*y**2 - 4*z**2, "
                          "r_and((x-0.4)**2 + y**2 - 0.0225, (x+0.4)**2 + y**2 - 0.0225))")
    r = triangulate_object(obj, qlev=6)
    m = r.metrics
    assert m.topology.watertight and m.topology.genus == 2
    assert m.projected_max < 0.05 * m.voxel
    assert m.angles.below_20 < 0.02 and m.edge_cv < 0.3 and m.face_normal_mean < 3

"""The whole mesher on the paper's surfaces: angle bound, border accuracy, trim, welded seams."""

import json

import numpy as np
import pytest

from algorithms.demos import demo
from algorithms.expr import ExpressionError
from algorithms.hybrid.mesher import mesh_hybrid
from algorithms.hybrid.spec import load_spec, spec_from_dict
from algorithms.io import InputError
from algorithms.metrics import topology
from algorithms.topology import boundary_loops


def run(name, **kw):
    spec = load_spec(demo(name, "hybrid").path)
    return spec, mesh_hybrid(spec.model, spec.params(**kw))


def check_common(spec, r, min_angle=30.0):
    m = spec.model
    size = m.surface.size
    s = r.stats_excluding_corners
    assert s.min >= min_angle, s
    assert r.stats_after.median > 44
    assert r.stats_before.min < 20  # Stage II alone is poor: the refinement did the work
    assert r.max_border_distance < 1e-8 * size
    # no triangle outside the trim: W > 0 at every triangle's (u, v) centroid
    c = r.uv[r.faces].mean(axis=1)
    assert np.all(m.W(c[:, 0], c[:, 1]) > 0)
    # the faces wind the same way in (u, v): every triangle counter-clockwise
    t = r.uv[r.faces]
    area = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
    assert np.all(area > 0)


def test_bezier_hole_angle_bound():
    spec, r = run("bezier-hole", max_edge=0.3)
    assert 500 < len(r.faces) < 3000
    check_common(spec, r)
    topo = topology(r.mesh.faces)
    assert topo.components == 1 and topo.boundary_loops == 2 and topo.genus == 0 and topo.oriented
    # the hole loop lies on the cylinder y^2 + z^2 = 0.16
    loops = boundary_loops(r.mesh.faces)
    rad = [np.hypot(*r.mesh.vertices[lp][:, 1:].T) for lp in loops]
    assert sum(np.allclose(x, 0.4, atol=1e-12) for x in rad) == 1


def test_dome_is_doubly_curved_and_bounded():
    spec, r = run("dome", max_edge=0.35)
    check_common(spec, r)
    # doubly curved: x depends on v too (not developable like the paper's patch)
    s = spec.model.surface
    assert abs(s(0.5, 0.5)[0] - s(0.5, 0.1)[0]) > 0.5


def test_interstage_seam_welded_loops():
    spec, r = run("interstage", max_edge=0.4)
    check_common(spec, r)
    topo = topology(r.mesh.faces)
    assert topo.components == 1 and topo.manifold_edges and topo.oriented
    loops = boundary_loops(r.mesh.faces)
    assert len(loops) == 12  # 10 openings (three through-hatches cut both sides) + 2 rims
    v = r.mesh.vertices
    rims = [lp for lp in loops if np.allclose(v[lp][:, 1], 0) or np.allclose(v[lp][:, 1], 3.0)]
    assert len(rims) == 2
    F = spec.model.F
    for lp in loops:
        if not any(lp is x for x in rims):
            assert np.abs(F(v[lp])).max() < 1e-10
    # the seam is welded: no vertex twice at the same place
    from scipy.spatial import cKDTree
    assert not cKDTree(v).query_pairs(1e-9)


def test_torus_both_seams_welded():
    spec, r = run("torus-windows", max_edge=0.5)
    topo = topology(r.mesh.faces)
    assert topo.components == 1 and topo.boundary_loops == 6 and topo.genus == 1 and topo.oriented
    assert r.stats_excluding_corners.min >= 30


def test_spec_rejects_unsafe_text_and_bad_fields():
    base = {"name": "x", "surface": {"type": "cylinder", "radius": 1, "z0": 0, "z1": 1}}
    with pytest.raises((InputError, ExpressionError)):
        spec_from_dict({**base, "trim": "__import__('os').system('true')"})
    with pytest.raises(InputError, match="surface.type"):
        spec_from_dict({"surface": {"type": "klein"}})
    with pytest.raises(InputError, match="mesh"):
        spec_from_dict({**base, "mesh": {"speed": 3}})
    s = spec_from_dict({**base, "constants": {"r": 0.5}, "trim": "r_not(circle_z(x, z - 0.5, r))"})
    assert s.model.F(np.array([[0.2, 0.0, 0.5]])) < 0 < s.model.F(np.array([[-1.0, 0.0, 0.5]]))


def test_cli_writes_mesh_report_histogram(tmp_path):
    from algorithms.cli import main

    out, rep, png = tmp_path / "m.ply", tmp_path / "r.json", tmp_path / "h.png"
    args = ["hybrid", "--demo", "cylinder-windows", "-o", str(out), "--max-edge", "0.5",
            "--report", str(rep), "--hist", str(png)]
    assert main(args) == 0
    d = json.loads(rep.read_text())
    assert d["angles_after"]["min"] >= 30 and d["topology"]["boundary_loops"] == 6
    assert d["counts"]["triangles_final"] == sum(d["histogram"]["after"])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(args) == 2  # refuses to overwrite
    assert main(args + ["--force"]) == 0

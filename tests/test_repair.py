import json

import numpy as np
import pytest
from conftest import data_file

from algorithms.cases import band, cut
from algorithms.cli import main
from algorithms.demos import demo
from algorithms.io import load_model, load_raw
from algorithms.mesh import Icadm, Mesh
from algorithms.metrics import distances, topology
from algorithms.normalize import normalize
from algorithms.repair import RepairParams, repair
from algorithms.topology import islands


def face_keys(v, f):
    t = np.round(np.asarray(v)[np.asarray(f)], 9)
    t = np.sort(t.view([("x", float), ("y", float), ("z", float)]).reshape(len(f), 3), axis=1)
    return {row.tobytes() for row in t}


def assert_input_kept(model: Icadm, out: Mesh):
    kin = face_keys(model.mesh.vertices, model.mesh.faces)
    kout = face_keys(out.vertices, out.faces)
    assert kin <= kout, f"{len(kin - kout)} input faces changed or lost"


def run_demo(name, **kw):
    model = load_model(demo(name).path)
    res = repair(model, RepairParams(**kw))
    assert_input_kept(model, res.mesh)
    return model, res


def test_two_caps_become_one_closed_sphere():
    model, res = run_demo("two-caps")
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0
    assert res.class_found == "ICM3"
    assert sum(b.kind == "island" for b in res.bridges) >= 2


def test_four_islands_become_one_closed_surface():
    _, res = run_demo("four-islands")
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0


def test_cut_torus_comes_back_as_a_torus():
    _, res = run_demo("cut-torus")
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 1
    assert res.class_found == "ICMT"


def test_sphere_with_two_small_holes_grows_no_handle():
    _, res = run_demo("two-holes")
    t = topology(res.mesh.faces)
    assert t.watertight and t.genus == 0
    assert not any(b.kind == "tunnel" for b in res.bridges)


def test_big_curved_hole_is_closed_near_the_truth():
    model, res = run_demo("big-hole")
    t = topology(res.mesh.faces)
    assert t.watertight and t.genus == 0
    tv, tf = load_raw(demo("big-hole").truth)
    d = distances(res.mesh.vertices, res.mesh.faces, tv, tf, samples=4000)
    assert d.hausdorff < 0.03


def test_three_islands_of_a_capsule():
    import trimesh

    cap = trimesh.creation.capsule(height=2.0, radius=0.6, count=[32, 32])
    v, f = trimesh.remesh.subdivide_to_size(cap.vertices, cap.faces, max_edge=0.12)
    truth = Mesh(v, f)
    c = cut(truth, band(truth, 2, -0.55, -0.35) | band(truth, 2, 0.35, 0.55), name="capsule", description="")
    model = normalize(c.incomplete.vertices, c.incomplete.faces)
    assert islands(model.mesh.faces)[0] == 3
    res = repair(model)
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0
    assert_input_kept(model, res.mesh)


def test_every_stage_recorded_and_cancel(tmp_path):
    model = load_model(demo("two-caps").path)
    seen = []
    res = repair(model, progress=lambda f, m: seen.append(f))
    assert [s.name for s in res.stages][:3] == ["input", "bridges", "holes"]
    assert seen[-1] == 1.0 and all(0 <= f <= 1 for f in seen)
    from algorithms.records import Cancelled

    with pytest.raises(Cancelled):
        repair(model, cancel=lambda: True)


def test_params_validation():
    with pytest.raises(ValueError, match="parameter darning="):
        RepairParams(darning="glue")
    with pytest.raises(ValueError, match="parameter tunnels="):
        RepairParams(tunnels="maybe")


def test_cli_repair_report_and_no_overwrite(tmp_path, capsys):
    out, rep = tmp_path / "o.ply", tmp_path / "r.json"
    assert main(["repair", "--demo", "two-caps", "-o", str(out), "--report", str(rep), "--quiet"]) == 0
    r = json.loads(rep.read_text())
    for key in ("params", "class", "set_aside", "bridges", "holes", "output", "timings"):
        assert key in r
    assert r["output"]["watertight"] and r["output"]["components"] == 1 and r["output"]["genus"] == 0
    before = out.read_bytes()
    assert main(["repair", "--demo", "two-caps", "-o", str(out), "--quiet"]) == 2
    assert out.read_bytes() == before


def test_real_bunny_main_island_closed(tmp_path):
    model = load_model(data_file("bunny.ply"))
    res = repair(model)
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0
    rep = res.report()
    assert rep["set_aside"]["count"] == len(model.set_aside) > 80
    assert_input_kept(model, res.mesh)

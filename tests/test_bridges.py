"""Candidate bridges between islands (§6 step 1) and `bridgefield bridges`."""

import json

import numpy as np
import pytest

from algorithms.boundary import summarize
from algorithms.bridges import BridgeSet, Candidate, find_candidate_bridges, trace_from_vertex
from algorithms.cases import combine, disk
from algorithms.cli import main
from algorithms.io import save_mesh
from algorithms.mesh import Icadm, Mesh
from algorithms.params import FieldParams
from algorithms.records import Cancelled


def two_disks(flip=False):
    return Icadm(combine(disk((0, 0, 0)), disk((2.6, 0, 0), flip=flip)))


@pytest.mark.parametrize("mode", ["light", "full"])
def test_two_coplanar_disks_give_bridges_from_one_disk_to_the_other(mode):
    m = two_disks()
    bs = find_candidate_bridges(m, FieldParams(mode=mode))
    assert isinstance(bs, BridgeSet) and all(isinstance(c, Candidate) for c in bs.candidates)
    arrived = bs.arrived()
    assert len(arrived) >= 2
    for c in arrived:
        assert {c.line.start_island, c.line.end_island} == {0, 1}
        assert c.quality > 0 and c.factors.qT > 0.9 and c.factors.Q > 0
    loops = summarize(m).loops
    assert len(bs.attraction) == len(loops)
    assert [len(w) for w in bs.attraction] == [len(lp.vertices) for lp in loops]
    assert bs.lc > 0 and bs.params.lc == bs.lc and set(bs.timings) >= {"attraction", "tracing", "total"}
    # the candidate records where it started
    for c in bs.candidates:
        assert loops[c.start_loop].vertices[c.start_index] == c.line.start_vertex


def test_flipped_second_disk_gives_no_bridge():
    for mode in ("light", "full"):
        bs = find_candidate_bridges(two_disks(flip=True), FieldParams(mode=mode))
        assert bs.arrived() == []


def hinged(deg):
    """Disk B2 left of disk A, hinged by deg about its point nearest A: it leaves A's plane."""
    d = disk((-2.6, 0, 0))
    a = np.radians(deg)
    piv = np.array([-1.6, 0, 0])
    R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    return Mesh((d.vertices - piv) @ R.T + piv, d.faces)


def test_ki_raises_the_tangential_candidate_against_the_angled_one():
    m = Icadm(combine(disk((0, 0, 0)), disk((2.6, 0, 0)), hinged(60)))
    ratios = []
    for ki in (0.0, 1.0, 3.0):
        bs = find_candidate_bridges(m, FieldParams(ki=ki, lc=0.6))
        from_a = {c.line.end_island: c for c in bs.arrived() if c.line.start_island == 0}
        assert set(from_a) == {1, 2}
        assert from_a[1].factors.q4 > from_a[2].factors.q4
        ratios.append(from_a[1].quality / from_a[2].quality)
    assert ratios[0] < ratios[1] < ratios[2]


def test_trace_from_vertex_and_cancel():
    m = two_disks()
    ln = trace_from_vertex(m, FieldParams(lc=0.6), 193)
    assert ln.arrived and ln.end_vertex == 257 + 193 + 32
    with pytest.raises(ValueError, match="not a boundary vertex"):
        trace_from_vertex(m, FieldParams(), 0)
    with pytest.raises(Cancelled):
        find_candidate_bridges(m, FieldParams(), cancel=lambda: True)
    seen = []
    find_candidate_bridges(m, FieldParams(), progress=lambda f, what: seen.append(f))
    assert seen[0] == 0.0 and seen[-1] == 1.0


def test_single_island_with_two_loops_uses_the_loops():
    from algorithms.demos import demo
    from algorithms.io import load_model

    m = load_model(demo("cut-torus", "repair").path)
    bs = find_candidate_bridges(m, FieldParams())
    arrived = bs.arrived()
    assert len(arrived) >= 2
    loops = summarize(m).loops
    vl = {int(v): k for k, lp in enumerate(loops) for v in lp.vertices}
    assert all(vl[c.line.start_vertex] != vl[c.line.end_vertex] for c in arrived)


def test_cli_bridges_report(tmp_path, capsys):
    src = tmp_path / "disks.ply"
    save_mesh(combine(disk((0, 0, 0)), disk((2.6, 0, 0))), src)
    rep = tmp_path / "r.json"
    assert main(["bridges", str(src), "--mode", "full", "--ki", "0.5", "--report", str(rep)]) == 0
    d = json.loads(rep.read_text())
    assert {"params", "timings", "bridges", "lc", "attraction"} <= set(d)
    assert d["params"]["mode"] == "full" and d["params"]["ki"] == 0.5
    assert d["bridges"]
    for b in d["bridges"]:
        assert {"from_island", "from_vertex", "to_island", "to_vertex", "status", "length", "quality", "steps",
                "points"} <= set(b)
        assert b["status"] == "arrived" and {b["from_island"], b["to_island"]} == {0, 1}
        assert len(b["points"]) == b["steps"] and b["quality"] > 0
    out = capsys.readouterr().out
    assert "arrived" in out
    # never overwrite without --force
    assert main(["bridges", str(src), "--report", str(rep)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["bridges", str(src), "--report", str(rep), "--force", "--tracer", "predictor-corrector"]) == 0
    assert json.loads(rep.read_text())["params"]["tracer"] == "predictor-corrector"
    assert main(["bridges", str(src), "--ki", "-1"]) == 2
    assert "ki" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["two-caps", "four-islands"])
def test_cli_demos(name, capsys):
    assert main(["bridges", "--demo", name, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    arrived = [b for b in d["bridges"] if b["status"] == "arrived"]
    assert len(arrived) >= 4
    assert all(b["from_island"] != b["to_island"] and b["quality"] > 0 for b in arrived)

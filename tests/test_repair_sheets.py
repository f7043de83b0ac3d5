"""A hole punched through a thin sheet: two loops a sheet's thickness apart, one on each side.
They are two holes to cap, not the rims of a tunnel (repair_field.through_sheet)."""

from __future__ import annotations

import numpy as np
import pytest
from test_repair import assert_input_kept

import algorithms.repair_field as rf
from algorithms import cases as gen
from algorithms.metrics import distances, topology
from algorithms.normalize import normalize
from algorithms.params import FieldParams
from algorithms.records import ARRIVED, ForceLine
from algorithms.repair import RepairParams, repair
from bench.cases import ball


def _line(points, start: int = 0, end: int = 1) -> ForceLine:
    p = np.asarray(points, dtype=np.float64)
    z = np.zeros_like(p)
    return ForceLine(p, z, z, np.zeros(len(p)), ARRIVED, start, 0, end, 0)


def test_through_sheet_when_the_line_enters_the_solid_at_both_ends():
    up, down = np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0])
    # straight down from the top side (normal up) to the bottom side (normal down) of a sheet
    assert rf.through_sheet(_line([[0, 0, 0.06], [0, 0, 0.0], [0, 0, -0.06]]), {0: up, 1: down})
    # 40 degrees off the normal at both ends: still through (-n . d = cos 40 = 0.77 > 0.7)
    a = np.radians(40)
    assert rf.through_sheet(_line([[0, 0, 0], [np.sin(a), 0, -np.cos(a)]]), {0: up, 1: down})
    # 50 degrees off: not (cos 50 = 0.64)
    a = np.radians(50)
    assert not rf.through_sheet(_line([[0, 0, 0], [np.sin(a), 0, -np.cos(a)]]), {0: up, 1: down})
    # between two faces that look the same way, a step apart (featuretype cut by a slab: two walls
    # facing -y, 0.09 apart):
    # the line enters one and leaves the other
    assert not rf.through_sheet(_line([[0, 0, 0], [0, 0, -0.1]]), {0: up, 1: up})
    # across a gap between two faces that look at each other (outside the solid at both ends)
    assert not rf.through_sheet(_line([[0, 0, 0], [0, 0, 0.1]]), {0: up, 1: down})
    # along a tube cut across: the line continues both surfaces (normals across the line)
    side = np.array([0.0, 1.0, 0.0])
    assert not rf.through_sheet(_line([[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]), {0: side, 1: side})
    # into the solid at one end only (a through-hole's wall joined to the face it opens onto): kept
    assert not rf.through_sheet(_line([[0, 0, 0], [0, 0, -0.5], [0, 0, -1]]), {0: up, 1: side})
    # the direction is taken half the line's length away: a line that leaves along the surface
    # and only then turns down is not through
    bent = [[0, 0, 0], [0.4, 0, 0], [0.5, 0, -0.1], [0.5, 0, -0.5]]
    assert not rf.through_sheet(_line(bent), {0: up, 1: up})
    # an end whose normal is unknown (not a loop vertex) is never through
    assert not rf.through_sheet(_line([[0, 0, 0], [0, 0, -1]]), {0: up})


def test_through_sheet_reads_the_chord_of_a_line_that_leaves_along_the_surface(monkeypatch):
    """A line from the top side of a sheet 0.12 thick that leaves nearly along it (its point half
    its length away 79 degrees off the inward normal) and then goes down to the bottom side: its
    chord is 40 degrees off both normals (-n . d = 0.77): through (SHEET_CHORD); without the chord,
    not. A chord 50 degrees off: not through."""
    up, down = np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0])
    a = np.radians(40)
    x = 0.12 * np.tan(a)
    late = _line([[0, 0, 0], [x, 0, -0.02], [x, 0, -0.12]])
    assert rf.through_sheet(late, {0: up, 1: down})
    monkeypatch.setattr(rf, "SHEET_CHORD", False)
    assert not rf.through_sheet(late, {0: up, 1: down})
    monkeypatch.setattr(rf, "SHEET_CHORD", True)
    x = 0.12 * np.tan(np.radians(50))
    assert not rf.through_sheet(_line([[0, 0, 0], [x, 0, -0.02], [x, 0, -0.12]]), {0: up, 1: down})


def test_two_holes_one_above_the_other_on_a_thin_plate_are_capped(monkeypatch):
    """bench/sweep.py thin-plate:30:1 (light): two ball cuts on the two faces of the plate (0.12
    thick) at x 0.4-1.1, one above the other. Three lines left the lower hole almost along the plate,
    rose through it and reached the upper hole: their chords 43 degrees off the normals, the point
    half their length away 55-60. Read by the chord they run through a sheet: the holes are capped,
    genus 0 (without the chord: a tunnel, genus 1)."""
    from test_repair_random_cuts import closed_repair, sweep_model

    model = sweep_model("thin-plate", 30, 1)
    closed_repair(model, genus=0)  # closed, one piece, every input face kept
    monkeypatch.setattr(rf, "SHEET_CHORD", False)
    assert topology(repair(model, RepairParams(field=FieldParams(mode="light"))).mesh.faces).genus == 1


@pytest.mark.parametrize("mode", ["light", "full"])
def test_a_hole_punched_through_a_thin_sheet_is_capped_on_both_sides(mode, monkeypatch):
    truth = gen.plate((3.0, 2.0, 0.12))
    case = gen.cut(truth, ball(truth, np.array([0.0, 0.0, 0.06]), 0.2), name="sheet", description="",
                   free_points=0, seed=1)
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    params = RepairParams(field=FieldParams(mode=mode))
    res = repair(model, params)
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0, res.tunnel_note
    assert "run through a sheet, entering both its sides: they join neither" in res.tunnel_note
    assert_input_kept(model, res.mesh)
    # the two caps are flat: the truth's two sides, to within a small fraction of the thickness
    d = distances(res.mesh.vertices, res.mesh.faces, truth.vertices, truth.faces)
    assert d.hausdorff * truth.bbox_diagonal() < 0.01 * 0.12
    # without the test the two short lines through the sheet beat the lines across each hole and
    # the sheet gets a tunnel: genus 1
    monkeypatch.setattr(rf, "through_sheet", lambda *a, **k: False)
    res = repair(model, params)
    assert topology(res.mesh.faces).genus == 1
    assert "a tunnel" in res.tunnel_note


def test_lines_through_a_sheet_between_two_loops_join_neither(monkeypatch):
    """featuretype, sweep cut 3:1 (bench/sweep.py: a slab along a row of through-holes): two lines
    between loops run through the part's wall; as lines that join neither they beat the lines of
    loops 3 and 4, which were a spurious tunnel before (genus 10). The counterfactual is the run
    with the pinches' copies apart (the repair's first run): the second, with them joined by pinch
    bridges, refuses that tunnel too. The lines that cut across surface that is there
    (repair_field.surface_shortcuts) change the first run's tunnels (genus 8 as written, 16 copies
    apart; the repair's result is 9 either way), so the counterfactual runs with that test off.
    Loop 4's lines to loop 3 all win, so the one-sided rule (repair_field.ONE_SIDED) proposes that
    tunnel again; the pinch joins refuse it (repair.PAST_A_PINCH) and the result is 9. The sheet
    rule is read with the one-sided rule off."""
    from algorithms.repair import _repair
    from bench.sweep import make_cut

    case = make_cut("featuretype", 3, 1)
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 9, res.tunnel_note
    assert "loops 3 and 4: 9 lines join them, a tunnel (one loop's lines to the other all win)" in res.tunnel_note
    monkeypatch.setattr(rf, "ONE_SIDED", False)
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    assert topology(res.mesh.faces).genus == 9
    assert "loops 3 and 4: 9 lines join them, beaten" in res.tunnel_note
    assert_input_kept(model, res.mesh)
    params = RepairParams(field=FieldParams(mode="light"))
    monkeypatch.setattr(rf, "SHORTCUT", 0.0)
    assert topology(_repair(model, params).mesh.faces).genus == 9
    monkeypatch.setattr(rf, "through_sheet", lambda *a, **k: False)
    res = _repair(model, params)  # the first run
    assert topology(res.mesh.faces).genus == 10


@pytest.mark.parametrize("mode", ["light", "full"])
def test_islands_joined_elsewhere_get_no_handle_through_a_wall(mode, monkeypatch):
    """bench/sweep.py frep-bowl:35:0: slabs parted the bowl's outer and inner faces into bands (three
    islands), and a ball took the bottom through the wall. The bands' bridges join the islands; all
    17 lines between the two bottom holes (a wall's thickness apart) run through the wall, none of
    the bands' 192. Step 1 read their ring as the handle of a torus cut into pieces (genus 1, truth
    0, 4.7 % off the truth); a handle there now needs lines that do not run through a sheet
    (repair.SHEET_HANDLES): both bottom holes are capped."""
    from test_repair_random_cuts import sweep_model

    import algorithms.repair as rp
    from bench.sweep import cut_named

    model = sweep_model("frep-bowl", 35, 0)
    params = RepairParams(field=FieldParams(mode=mode))
    res = repair(model, params)
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0
    assert any(why == rp.SHEET_HANDLE for _, why in res.rejected)
    assert_input_kept(model, res.mesh)
    truth = cut_named("frep-bowl:35:0").truth
    d = distances(res.mesh.vertices, res.mesh.faces, truth.vertices, truth.faces)
    assert d.hausdorff < 0.01  # relative to the diagonal (4.7 % with the handle)
    monkeypatch.setattr(rp, "SHEET_HANDLES", False)
    assert topology(repair(model, params).mesh.faces).genus == 1


def test_sheet_pairs_need_half_their_lines_through_the_sheet():
    """repair._sheet_pairs on hand-made lines: loops 0 and 1 are the two sides of a plate (normals
    +z and -z, 0.1 apart), loop 2 beside loop 0 on the top face. Lines straight through the plate
    enter both sides; lines along the top face do not."""
    from algorithms.bridge_graph import Bridge
    from algorithms.repair import _sheet_pairs

    class Frame:
        def __init__(self, vertices, normal):
            self.vertices = np.asarray(vertices)
            self.normal = np.tile(normal, (len(vertices), 1))

    frames = [Frame([0, 1], [0, 0, 1.0]), Frame([2, 3], [0, 0, -1.0]), Frame([4, 5], [0, 0, 1.0])]
    loop_of = {0: (0, 0), 1: (0, 1), 2: (1, 0), 3: (1, 1), 4: (2, 0), 5: (2, 1)}

    def cand(a, b, points):
        return Bridge(a, b, np.zeros((0, 3)), 1.0, "island"), _line(points, a, b)

    down = [[0, 0, 0.1], [0, 0, 0.05], [0, 0, 0.0]]  # top face of the plate to the bottom face
    aside = [[0, 0, 0.1], [0.5, 0, 0.15], [1.0, 0, 0.1]]  # along the top face
    assert _sheet_pairs([cand(0, 2, down), cand(1, 3, down), cand(0, 4, aside)], loop_of, frames) == {(0, 1)}
    # half through: still a sheet pair; fewer: not
    assert _sheet_pairs([cand(0, 2, down), cand(1, 3, aside)], loop_of, frames) == {(0, 1)}
    assert _sheet_pairs([cand(0, 2, down), cand(1, 3, aside), cand(0, 3, aside)], loop_of, frames) == set()

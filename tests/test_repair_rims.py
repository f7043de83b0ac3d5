"""Holes along a sharp rim: the fill continues the face of the part it lies in, not the face beyond
the rim (darning/sheets.py), the crease the border already follows is not continued again by a
chain (creases.CreaseEnds.at), the angle polish keeps its points on the surface in a concave
corner (refine._move_best), and a fine rim cut half away is continued along its own circle
(creases.crease_ends)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import trimesh
from test_repair import assert_input_kept

import algorithms.darning  # noqa: F401  (the package re-exports a function named refine)
import algorithms.darning.sheets as sheets
from algorithms import cases as gen
from algorithms.mesh import Mesh
from algorithms.metrics import distances, point_to_surface, topology
from algorithms.normalize import normalize
from algorithms.repair import RepairParams, repair

R = sys.modules["algorithms.darning.refine"]


def _box_hole(across: bool):
    """A box (2 x 2 x 1, each face in 64 triangles) with faces removed near the middle of its top's
    +y edge: top faces only (the hole's border runs along the edge), or top and side faces (the
    edge crosses the hole)."""
    box = gen.subdivided(trimesh.creation.box((2.0, 2.0, 1.0)), 3)
    V, F, n = box.vertices, box.faces, box.face_normals
    c = V[F].mean(axis=1)
    top, side = n[:, 2] > 0.9, n[:, 1] > 0.9
    if across:
        return V, F, n, (top | side) & (np.linalg.norm(c - [0.0, 1.0, 0.5], axis=1) < 0.45)
    return V, F, n, top & (np.linalg.norm(c[:, :2] - [0.0, 1.0], axis=1) < 0.45)


def test_the_face_beyond_a_rim_the_border_runs_along_is_left_out():
    V, F, n, hole = _box_hole(across=False)
    out = sheets.along_crease(V, F, ~hole, hole, 40.0)
    assert np.array_equal(out, ~hole & (n[:, 1] > 0.9))  # the whole +y side, nothing else
    # the fairing system of the fill reads the top only: 128 faces (a side of 8 x 8 x 2), the fill's
    # 12 among them; the vertices of the rim between the fill and the side read positions only
    free = np.unique(F[hole])
    free = free[np.abs(V[free, 1]) < 0.999]
    keep, bare = sheets.sheet_system(V, F, ~hole, free, 40.0, region=hole)
    assert keep.sum() == 128 and np.all(n[keep, 2] > 0.9)
    assert len(bare) and np.allclose(V[bare, 2], 0.5)


def test_a_rim_that_crosses_the_hole_leaves_both_faces_in():
    V, F, n, hole = _box_hole(across=True)
    assert not sheets.along_crease(V, F, ~hole, hole, 40.0).any()
    free = np.setdiff1d(np.unique(F[hole]), np.unique(F[~hole]))
    keep, _ = sheets.sheet_system(V, F, ~hole, free, 40.0, region=hole)
    assert np.array_equal(keep, (n[:, 2] > 0.9) | (n[:, 1] > 0.9))  # the top and the +y side


def test_move_best_keeps_a_vertex_whose_ring_lies_along_a_line(monkeypatch):
    """Slivers along a crease: the ring (five points on a shallow arc) spans no plane to move in."""
    x = np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    p = np.vstack([np.stack([x, 0.02 * x**2, np.zeros(5)], axis=1), [[0.0, 0.2, 0.3]]])
    star = np.array([[5, i, i + 1] for i in range(4)] + [[5, 4, 0]], dtype=np.int64)
    before = R.corner_angles(p, star).min()
    q = p.copy()
    assert not R._move_best(q, star, 5, before)
    assert np.array_equal(p, q)
    monkeypatch.setattr(R, "RING_LINE", 0.0)  # as before: the search in the plane of the star's normals
    monkeypatch.setattr(R, "ON_STAR", False)  # moved it 1.15 away
    assert R._move_best(q, star, 5, before) and np.linalg.norm(q[5] - p[5]) > 1.0


def _sweep_cut(name: str):
    from bench.sweep import make_cut

    model, seed, i = name.split(":")
    return make_cut(model, int(seed), int(i))


def _hausdorff(case, model, genus: int | None = None) -> float:
    """The repair of a sweep cut: every input face kept, closed, one piece of ``genus`` (when given);
    its Hausdorff distance to the truth (a fraction of the diagonal)."""
    out = repair(model, RepairParams()).mesh
    assert_input_kept(model, out)
    if genus is not None:
        t = topology(out.faces)
        assert t.watertight and t.components == 1 and t.genus == genus
    return distances(out.vertices, out.faces, case.truth.vertices, case.truth.faces).hausdorff


def test_the_angle_polish_keeps_its_points_on_the_surface_in_a_concave_corner(monkeypatch):
    """bench/sweep.py cut mushroom:5:0: a fill in the concave corner under the mushroom's cap. The
    polish moved two points in planes its sliver stars tilted, 0.10-0.11 into the cap (3.8 % of
    the diagonal); kept within a quarter of their stars' reach from the stars' old faces (the guard
    before), 0.048; on the old faces (refine.ON_STAR), the farthest new vertex is 0.003 off. (With
    the guards off, 0.098 since the rim's ends read its circle over notches, creases.CreaseEnds.at.)
    Since the copies of the cut's pinched vertices are joined (algorithms/copies.py) the polish
    meets other faces there; the guards are measured on the patches as they were before the joins."""
    import algorithms.repair as rp
    from algorithms.copies import Joined

    case = _sweep_cut("mushroom:5:0")
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    out = repair(model, RepairParams()).mesh
    assert_input_kept(model, out)
    n_in = len(model.mesh.vertices)
    err = point_to_surface(out.vertices[n_in:], case.truth.vertices, case.truth.faces)
    assert err.max() < 0.01, err.max()
    monkeypatch.setattr(rp, "join_copies", lambda V, F, *a, **k: Joined(np.array(V), np.array(F), 0, 0, 0))
    out = repair(model, RepairParams()).mesh
    err = point_to_surface(out.vertices[n_in:], case.truth.vertices, case.truth.faces)
    assert err.max() < 0.01, err.max()
    monkeypatch.setattr(R, "ON_STAR", False)  # the guards off: as before
    monkeypatch.setattr(R, "RING_LINE", 0.0)
    out = repair(model, RepairParams()).mesh
    err = point_to_surface(out.vertices[n_in:], case.truth.vertices, case.truth.faces)
    assert err.max() > 0.05, err.max()


def test_a_hole_on_a_face_along_a_sharp_rim_continues_that_face(monkeypatch):
    """bench/sweep.py cut mushroom:6:0: a hole on the cap's nearly flat underside, its border along
    the sharp rim. Read with the rim's other face, the fill sagged 0.75 % of the diagonal below the
    truth (MeshLib's: 0.01 %); read by sheet (darning/sheets.py), 0.013 %. The rim's ends read as
    its circle (creases.LINE) and the border follows it into another end: no chain is made, and the
    patch is kept as darn faired it (repair.RIM_PIN); projected by the APSS, which rounds the rim
    off, it was 0.29 % off. The fill kept inside the planes of the convex faces round it
    (repair.CONVEX_CLAMP) is 0.01 % off with either mechanism off."""
    import algorithms.repair as rp

    case = _sweep_cut("mushroom:6:0")
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    h = _hausdorff(case, model, genus=0)
    assert h < 0.0005, h
    # the convex clamp alone also keeps the fill on the face (the underside is convex round it):
    # each mechanism is checked with the clamp off
    monkeypatch.setattr(sheets, "along_crease", lambda v, f, *a, **k: np.zeros(len(f), dtype=bool))
    h = _hausdorff(case, model)
    assert h < 0.0005, h
    monkeypatch.setattr(rp, "CONVEX_CLAMP", False)
    h = _hausdorff(case, model)
    assert h > 0.005, h
    monkeypatch.undo()
    monkeypatch.setattr(rp, "CONVEX_CLAMP", False)
    monkeypatch.setattr(rp, "RIM_PIN", False)
    h = _hausdorff(case, model)
    assert h > 0.002, h


def _cylinder_rim_hole(subdivisions: int, radius: float):
    cyl = gen.subdivided(trimesh.creation.cylinder(radius=1.0, height=1.0, sections=48), subdivisions)
    truth = Mesh(cyl.vertices, cyl.faces)
    c = gen.face_centroids(truth)
    side = np.abs(cyl.face_normals[:, 2]) < 0.5
    return gen.cut(truth, side & (np.linalg.norm(c - [1.0, 0.0, 0.5], axis=1) < radius), name="cylinder-rim",
                   description="a hole in a cylinder's side along its top rim")


@pytest.mark.parametrize("subdivisions, radius, most", [(2, 0.4, 1e-6), (3, 0.4, 0.004), (2, 0.6, 0.007)])
def test_a_hole_along_a_cylinder_rim_keeps_the_cylinder(subdivisions, radius, most):
    """The rim of trimesh's 48-gon cylinder, subdivided, turns 7.5 degrees every few border edges.
    The crease ends at the two ends of the rim stretch walked along the border only 12 degrees from
    where they arrived, and were joined by a chain bulging 5 % outside the rim (Hausdorff 1.8 %,
    3.6 % on the wider hole); faired with the top's faces, the side bulged out 11 %."""
    case = _cylinder_rim_hole(subdivisions, radius)
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    res = repair(model, RepairParams())
    assert not [b for b in res.bridges if b.kind == "crease"]
    assert_input_kept(model, res.mesh)
    d = distances(res.mesh.vertices, res.mesh.faces, case.truth.vertices, case.truth.faces)
    assert d.hausdorff < most, d.hausdorff


def test_a_fine_rim_half_cut_away_is_read_as_its_circle(monkeypatch):
    """bench/sweep.py cut mushroom:10:1 (light mode): half the stem's wall under the cap is cut away.
    The stem's rim is a 256-gon whose points lie 1e-3 of its radius off the circle; the circle
    through the last three vertices at each end of the cut rim had radius 0.055 for 0.22, the two
    ends were continued along their tangents, and their rays met at a corner 0.26 from the axis:
    7.4 % of the diagonal. Fitted along the rim (creases.LONG_FIT), both ends read the rim's circle:
    3.6 % (MeshLib's: 4.2 %), the arc between them refused: it passed the border vertices on the
    rim, where the border zigzags along it. Walking on over those notches (creases.CreaseEnds.at),
    the ends meet along the rim: 0.66 %. (Three-point circles: tests/test_creases.py.)"""
    import algorithms.creases as C

    case = _sweep_cut("mushroom:10:1")
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    h = _hausdorff(case, model, genus=0)
    assert h < 0.01, h
    monkeypatch.setattr(C, "_on_circle", lambda p, c, tol=0.01: False)  # no steps over notches, as before
    h = _hausdorff(case, model)
    assert h > 0.03, h


def test_a_fillet_s_two_ends_are_not_joined_the_long_way_round(monkeypatch):
    """bench/sweep.py cut featuretype:8:1 (light mode): the two ends of a pocket corner's fillet
    arc, whose short arc the cut left, each continue the fillet's circle into the hole; with every
    arc joined (concave ones too), the chain ran 270 degrees round the circle, off the part: 10.5 %
    of the diagonal. No arc longer than half its circle (creases.MAX_ARC): 3.5 %. That is the
    repair's first run (38 copies apart); the run kept, with the pinches on one hole joined too
    (repair._pinch_joins), parts that hole at the pinches and no arc runs round it there: 3.6 %
    with the rule or without it. So the rule is checked on the first run."""
    import algorithms.creases as C
    from algorithms.repair import _repair

    case = _sweep_cut("featuretype:8:1")
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    h = _hausdorff(case, model)  # the genus is wrong on this cut (6 for 9: README, known limits)
    assert h < 0.045, h

    def first_run() -> float:
        out = _repair(model, RepairParams()).mesh
        assert_input_kept(model, out)
        return distances(out.vertices, out.faces, case.truth.vertices, case.truth.faces).hausdorff

    assert first_run() < 0.045
    monkeypatch.setattr(C, "MAX_ARC", 360.0)
    h = first_run()
    assert h > 0.08, h

"""Cuts of the CAD part (featuretype) that no bench case has. A slab across the part leaves a
two-face island whose two bridges end at neighbouring vertices of its loop; a force line then
split the hole by a bare chord between them, which already was the island's border edge: the
output had an edge with four faces. A bare chord that is an edge gets a vertex midway. The slab
also cuts through a through-hole whose rim is one loop and whose lower part joined the slab's loop,
which island bridges reach: the tunnel rule must consider that loop too (spec §6 step 2: all
non-trivial boundaries), or the part comes back with genus 7 instead of 9."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import data_file
from test_repair import assert_input_kept

import algorithms.repair_field as rf
from algorithms.boundary import summarize
from algorithms.cases import cut, face_centroids
from algorithms.io import load_raw
from algorithms.mesh import Mesh
from algorithms.metrics import topology
from algorithms.normalize import normalize
from algorithms.params import FieldParams
from algorithms.repair import RepairParams, repair
from algorithms.topology import edge_table


def test_slab_across_the_part_gives_a_manifold_surface():
    part = Mesh(*load_raw(data_file("featuretype.stl")))
    n = np.array([-0.3338057414969535, 0.38549451719908506, 0.8602137549197368])
    case = cut(part, np.abs(face_centroids(part) @ n - 1.4508043208078552) < 0.2771542226709827 / 2,
               name="featuretype slab", description="")
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    assert edge_table(res.mesh.faces).counts.max() == 2
    t = topology(res.mesh.faces)
    assert t.watertight and t.oriented and t.components == 1 and t.genus == 9
    # the slab leaves a row of one-face fragments, chained at their corners, along a cut wall; the
    # first hangs at the end of a tunnel bridge, which two walks pass: it joins its neighbours' walk
    assert_input_kept(model, res.mesh, fragments=True)


def test_fragment_between_two_holes_is_kept():
    """Five balls cut the part so that a two-face fragment touches two holes (and two one-face
    fragments hang at its corners): it joins the two holes into one walk; every input face stays."""
    part = Mesh(*load_raw(data_file("featuretype.stl")))
    c = face_centroids(part)
    remove = np.zeros(part.n_faces, dtype=bool)
    for v, r in ((483, 0.2925902196708333), (273, 0.5972613332249297), (267, 0.1744938932985518),
                 (233, 0.4367017851356098), (439, 0.3365696591901824)):
        remove |= np.linalg.norm(c - part.vertices[v], axis=1) < r
    case = cut(part, remove, name="featuretype five balls", description="")
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    assert sum(s.reason.startswith("fragment") for s in model.set_aside) == 4
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    assert res.attached is not None and len(res.attached.input_faces) == 4
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 9
    assert_input_kept(model, res.mesh)


def test_tunnel_between_two_small_loops_keeps_two_bridges():
    """A slab cuts the part through a through-hole: the hole's wall comes back as two loops of
    radius about 0.4 that 12 force lines join, the best in both directions (a lost handle). The
    part's boundary is coarse (mean edge 0.54), so the duplicate-bridge neighbourhood of the
    island graph (10 edges: 5.4, most of the part) made every second line a duplicate of the first
    and the tunnel was dropped with one bridge. Two bridges of a tunnel now duplicate only within
    the smaller loop's mean radius. (The truth has genus 9; two other lost handles, whose lines are
    beaten by lines across their own holes, are still not found. The slab also leaves rows of wall
    slivers touching the rims at single vertices: the run with their copies apart left 56 of them
    apart, genus 7 as written; the run with the pinches joined, kept, leaves fewer: genus 10 as
    written. Neither is right.)"""
    from algorithms.bridges import loop_radius
    from algorithms.repair import _repair

    part = Mesh(*load_raw(data_file("featuretype.stl")))
    n = np.array([0.3899871822577574, 0.19274635020369008, -0.9004214802845448])
    case = cut(part, np.abs(face_centroids(part) @ n + 0.1595052211916601) < 0.25290602953215924 / 2,
               name="featuretype slab through a hole", description="")
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    before = topology(model.mesh.faces)
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    tunnels = [b for b in res.bridges if b.kind == "tunnel"]
    assert len(tunnels) == 2
    frames = {v: f for f in summarize(model).loops for v in f.vertices}
    (fa, fb), (ga, gb) = ((frames[b.start], frames[b.end]) for b in tunnels)
    assert {id(fa), id(fb)} == {id(ga), id(gb)} and fa is not fb  # both join the same two loops
    radius = min(loop_radius(fa), loop_radius(fb))
    assert 0.3 < radius < 0.5
    V = model.mesh.vertices
    ends = [{id(frames[v]): V[v] for v in (b.start, b.end)} for b in tunnels]
    assert all(np.linalg.norm(ends[0][k] - ends[1][k]) >= radius for k in (id(fa), id(fb)))
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and before.genus == 6
    first = _repair(model, RepairParams(field=FieldParams(mode="light")))  # the pinches' copies apart
    assert topology(first.mesh.faces).genus == before.genus + 1
    assert any(b.kind == "pinch" for b in res.bridges) and res.copies_left < first.copies_left
    assert_input_kept(model, res.mesh, fragments=True)


def balls_and_slab(balls, normal, offset, width, *, seed, mode, free_points=100):
    """Featuretype cut by balls (centre, radius) and a slab |n.x - offset| < width / 2 (the sweep's
    random cuts, rebuilt from their parameters), normalised and repaired: (model, result)."""
    from test_repair_random_cuts import random_cut

    model = random_cut("featuretype.stl", balls, (normal, offset, width), free_points, seed)
    return model, repair(model, RepairParams(field=FieldParams(mode=mode)))


def test_merged_pinch_leaves_no_triangle_with_a_vertex_twice():
    """Four balls and a slab cut the part (with 100 free points, full mode). Darning one hole merges
    the copies of a pinched vertex; a later hole's walk passed a copy and its kept vertex one after
    the other, so after the merge it had an edge of length 0 and its patch a triangle with a vertex
    twice: a non-manifold edge, the output not closed. The merged walk now drops the repeat."""
    from algorithms.repair import _drop_repeats

    assert _drop_repeats((4, 7, 7, 9, 4)) == (7, 9, 4) and _drop_repeats((5, 5)) == (5,)
    model, res = balls_and_slab((((-2.5, 1.25, 0.0), 0.39079817572124387), ((2.5, -1.25, 1.0), 0.6278633883927272),
                                 ((2.5, 1.25, 0.5), 0.6675645780633177), ((2.5, 1.25, 1.0), 0.18430845133556156)),
                                (0.28712856930011993, 0.8948519015614418, 0.34175613961352297),
                                0.11389474323884632, 0.269427771705127, seed=15, mode="full")
    f = res.mesh.faces
    assert not ((f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])).any()
    assert edge_table(f).counts.max() == 2
    t = topology(f)
    assert t.watertight and t.components == 1 and t.genus == 9
    assert_input_kept(model, res.mesh, fragments=True)


def test_wall_triangles_touching_at_corners_close_into_one_surface(monkeypatch):
    """Three balls and a slab cut the part (100 free points). Along a cut wall the slab leaves a row
    of one-face islands, tall triangles that touch at their bottom corners (normalisation splits
    each shared corner into copies). Straight bridges from one corner to the next copy ran along
    the middle triangle's bottom edge; after the copies were merged they closed that triangle into
    a detached tetrahedron: two components. Bridges that run along the boundary are now refused
    (bridge_graph.BoundaryEdges): here the straight bridges that join what no force line joined and
    the sides of the non-disk walks."""
    model, res = balls_and_slab((((2.5, -1.25, 1.0), 0.6687600340474917), ((-2.5, -1.25, 1.0), 0.598631652103867),
                                 ((-2.5, 1.25, 1.0), 0.28165726468946073)),
                                (-0.6123935573972279, 0.7074217133214885, 0.352886171987027),
                                -0.31924636466848877, 0.26759478374547757, seed=15, mode="light")
    f = res.mesh.faces
    assert edge_table(f).counts.max() == 2
    t = topology(f)
    # the truth's 9. The tunnel's two lines meet at one end of the slab's loop and the second is
    # refused beside the first (left with one bridge); the two loops face each other
    # (repair_field.mutual_closest), so a straight bridge between their closest vertices is the
    # second. Without that: one handle short (8).
    assert t.watertight and t.oriented and t.components == 1 and t.genus == 9
    assert_input_kept(model, res.mesh, fragments=True)
    monkeypatch.setattr(rf, "MUTUAL_TUNNELS", False)
    _, res = balls_and_slab((((2.5, -1.25, 1.0), 0.6687600340474917), ((-2.5, -1.25, 1.0), 0.598631652103867),
                             ((-2.5, 1.25, 1.0), 0.28165726468946073)),
                            (-0.6123935573972279, 0.7074217133214885, 0.352886171987027),
                            -0.31924636466848877, 0.26759478374547757, seed=15, mode="light")
    assert topology(res.mesh.faces).genus == 8


def test_split_chord_between_copies_of_an_edge_gets_a_vertex():
    """Five balls and a slab cut the part (100 free points). A force line split a hole by a bare
    chord from vertex 562 to a copy of 542; the other copy and 562 bound an input border edge, so
    after the copies were merged the chord was that edge, with four faces. A bare chord that is an
    edge between copies now gets a vertex midway, as one between the same vertices did
    (repair._is_edge with the vertices' origins)."""
    from algorithms.repair import _is_edge

    F = np.array([[0, 1, 2]])
    origin = np.array([0, 1, 2, 1])  # vertex 3 is a copy of 1
    assert not _is_edge(F, 0, 3) and _is_edge(F, 0, 3, origin) and _is_edge(F, 3, 2, origin)
    assert not _is_edge(F, 3, 4, np.array([0, 1, 2, 1, 4]))
    # a kept bare bridge is an edge before any face has it (annulus sweep cut 4:0), a chained one is not
    from algorithms.bridge_graph import Bridge

    bare, chained = Bridge(4, 5, np.zeros((0, 3)), 1.0), Bridge(0, 4, np.zeros((1, 3)), 1.0)
    o6 = np.array([0, 1, 2, 1, 4, 5])
    assert _is_edge(F, 5, 4, o6, [bare]) and not _is_edge(F, 0, 4, o6, [chained, bare])
    none = np.zeros((0, 3), dtype=np.int64)  # no face: the bare bridge between copies alone
    assert _is_edge(none, 1, 2, origin, [Bridge(3, 2, np.zeros((0, 3)), 1.0)]) and not _is_edge(none, 1, 2, origin)
    model, res = balls_and_slab((((2.5, 1.25, 1.0), 0.6862816899052817), ((2.5, -1.25, 1.0), 0.5613853339011625),
                                 ((-2.5, -1.25, 1.0), 0.3540001044674994), ((-2.5, -1.25, 0.0), 0.6905120168834936),
                                 ((-2.5, 1.25, 1.0), 0.32992570011233185)),
                                (0.7780201606679658, 0.6151879892979507, 0.12739060961364929),
                                0.7113235660323769, 0.2070384305109183, seed=13, mode="light")
    f = res.mesh.faces
    assert edge_table(f).counts.max() == 2
    t = topology(f)
    # one handle short of the truth's 9 (two lines join loops 3 and 7, beaten by lines across
    # their own holes: the tunnel rule of spec §6 step 2 says no)
    assert t.watertight and t.oriented and t.components == 1 and t.genus == 8
    assert_input_kept(model, res.mesh, fragments=True)


def test_a_split_line_along_a_kept_wall_is_refused():
    """A band across the part (y = 0, width 3 % of the diagonal) takes the top and both end walls
    of the block at x 0.134..0.397, z 1.175..1.375, and keeps its side walls y = +-0.132. The hole
    round the block was split by a force line from corner to corner along the foot of the side wall
    y = 0.132: it runs on that wall's input edge, so it cut off a hole the shape of the wall, filled
    as a second sheet over it, and the rest of the block was darned as one saddle (2.1 % of the
    diagonal off the truth). A line whose middle runs on the input surface does not cross the hole
    (repair_field.runs_on_surface): split_line takes the next one (0.4 %; MeshLib's bridge fill 0.2 %)."""
    from algorithms.metrics import distances

    part = Mesh(*load_raw(data_file("featuretype.stl")))
    width = 0.03 * part.bbox_diagonal()
    case = cut(part, np.abs(face_centroids(part)[:, 1] - part.vertices[:, 1].mean()) < width / 2,
               name="featuretype band", description="")
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    t = topology(res.mesh.faces)
    assert t.watertight and t.oriented and t.components == 1 and t.genus == 9
    assert_input_kept(model, res.mesh)
    assert distances(res.mesh.vertices, res.mesh.faces, part.vertices, part.faces).hausdorff < 0.01


def test_a_crease_is_continued_once_across_scattered_small_holes():
    """4 % of the part's faces removed at random (the seeds 2 and 8 of numpy's default_rng): many
    holes of one or two faces. A used crease end keeps its face planes (CreaseEnds.use), and from
    them crease_line continued a crease again in each half of a two-face hole that a bent chain
    along that crease had split: a straight chord beside the chain on both sides, two faces of no
    area back to back and an edge with four faces (genus 8.5 and 8 as written, not watertight).
    A pair of border vertices is joined by one crease chain at most (CreaseEnds.joined)."""
    from bench.repair import merge_positions

    part = Mesh(*load_raw(data_file("featuretype.stl")))
    for seed in (2, 8):
        case = cut(part, np.random.default_rng(seed).random(part.n_faces) < 0.04, name=f"featuretype speckle {seed}",
                   description="")
        model = normalize(case.incomplete.vertices, case.incomplete.faces)
        res = repair(model, RepairParams(field=FieldParams(mode="light")))
        t = topology(res.mesh.faces)
        assert t.watertight and t.oriented and t.components == 1 and t.genus == 9
        merged = topology(merge_positions(np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces), 1e-9)[1])
        assert merged.watertight and merged.genus == 9
        pairs = [frozenset((b.start, b.end)) for b in res.bridges if b.kind == "crease"]
        assert len(pairs) == len(set(pairs))
        assert_input_kept(model, res.mesh)


@pytest.mark.parametrize(("name", "mode", "one_sided"), [("featuretype:41:0", "light", True),
                                                         ("featuretype:41:0", "full", True),
                                                         ("featuretype:35:1", "light", True),
                                                         ("featuretype:35:1", "full", False)])
def test_a_through_holes_rim_and_its_lower_wall_keep_the_handle(name, mode, one_sided, monkeypatch):
    """bench/sweep.py cuts 41:0 and 35:1: a ball took a through-hole's wall below its top rim, so the
    rim is one loop and the wall's lower part, down to the bottom mouth, another. Every line from
    the rim goes down to the lower loop; the lower loop's one line up loses to its short lines
    across the mouth between the feet of the wall's slivers. The rule read lines both ways, one
    side beaten, as no tunnel, and both ends were capped (genus 8). One loop's lines all winning,
    two or more, with a line back, now make the tunnel (repair_field.ONE_SIDED). (35:1 in full mode
    was right before: there lines both ways win.)"""
    from bench.sweep import cut_named

    case = cut_named(name)
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    res = repair(model, RepairParams(field=FieldParams(mode=mode)))
    t = topology(res.mesh.faces)
    assert t.watertight and t.oriented and t.components == 1 and t.genus == 9
    assert ("a tunnel (one loop's lines to the other all win)" in res.tunnel_note) == one_sided
    assert_input_kept(model, res.mesh, fragments=True)
    if one_sided:
        monkeypatch.setattr(rf, "ONE_SIDED", False)
        assert topology(repair(model, RepairParams(field=FieldParams(mode=mode))).mesh.faces).genus == 8

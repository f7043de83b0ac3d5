"""Coarsening after Stage III (coarsen.py): half-edge and midpoint collapses that keep every bound."""

import math
from dataclasses import replace

import numpy as np
import pytest
from test_hybrid_finish import build, plane

from algorithms.demos import demo
from algorithms.hybrid.chordal import chordal_errors
from algorithms.hybrid.coarsen import coarsen_pass
from algorithms.hybrid.mesher import HybridParams, mesh_hybrid
from algorithms.hybrid.spec import load_spec
from algorithms.metrics import min_angles, topology


def check_triangulation(tri):
    """Neighbours symmetric across shared edges, every live triangle counter-clockwise in (u, v)."""
    uv = np.array(tri.uv)
    for t, (al, tv, tn) in enumerate(zip(tri.alive, tri.tv, tri.tn)):
        if not al:
            continue
        a, b, c = (uv[i] for i in tv)
        assert (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0
        for k in range(3):
            n = tn[k]
            if n < 0:
                continue
            assert tri.alive[n]
            p, q = tv[(k + 1) % 3], tv[(k + 2) % 3]
            assert p in tri.tv[n] and q in tri.tv[n]
            assert t in tri.tn[n]


def hexagon_fan(centre=(0.0, 0.0)):
    """Six triangles around vertex 0 (a regular hexagon of radius 1 in the plane z = 0)."""
    ring = [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 7)[:-1]]
    uv = [centre] + ring
    faces = [[0, 1 + i, 1 + (i + 1) % 6] for i in range(6)]
    return build(plane(), uv, faces)


def test_collapse_removes_the_vertex_and_two_triangles_and_relinks_the_fan():
    tri = hexagon_fan()
    kept = tri.collapse(0, 1)
    assert tri.n_alive == 4 and len(kept) == 4
    f = tri.faces()
    assert 0 not in f
    assert sorted(map(sorted, f.tolist())) == [[1, 2, 3], [1, 3, 4], [1, 4, 5], [1, 5, 6]]
    check_triangulation(tri)
    with pytest.raises(ValueError):
        tri.collapse(2, 5)  # not neighbours


def test_coarsen_pass_removes_a_vertex_the_criteria_do_not_need_and_keeps_the_bounds():
    # the hexagon's centre: without a size criterion a collapse is admissible, but the new triangles
    # of a half-edge collapse onto a ring vertex have 30-degree angles, so a 31-degree bound forbids it
    # (the ring vertices are border-like here: they are the fan's outer vertices with open fans)
    tri = hexagon_fan()
    tri._add_segment(1, 2, 0)  # marks the ring as border: only the centre may go
    for i in range(2, 7):
        tri._add_segment(1 + (i - 1) % 6, 1 + i % 6, 0)
    assert coarsen_pass(tri, min_angle=31.0)[0] == 0
    assert tri.n_alive == 6
    done, changed = coarsen_pass(tri, min_angle=30.0 - 1e-9)
    assert done == 1 and changed.sum() == 7  # the centre and its ring
    assert tri.n_alive == 4
    assert min_angles(np.array(tri.p3), tri.faces()).min() == pytest.approx(30.0)
    # with a size limit shorter than the hexagon's diagonal nothing may go
    tri = hexagon_fan()
    for i in range(1, 7):
        tri._add_segment(i, 1 + i % 6, 0)
    assert coarsen_pass(tri, min_angle=20.0, max_edge=1.9)[0] == 0
    assert coarsen_pass(tri, min_angle=20.0, max_edge=2.1)[0] == 1


@pytest.mark.parametrize("name,tol", [("interstage", 2.5e-4), ("bezier-hole", 2.5e-4), ("dome", 5e-4)])
def test_coarsening_keeps_every_bound_with_fewer_triangles(name, tol):
    spec = load_spec(demo(name, "hybrid").path)
    surf = spec.model.surface
    eps = tol * surf.size
    base = replace(spec.params(), max_edge=None, chord_arc=0.0, max_deviation=eps)
    plain = mesh_hybrid(spec.model, replace(base, coarsen_angle=0.0))
    r = mesh_hybrid(spec.model, base)
    assert r.collapses > 0
    assert len(r.faces) < 0.9 * len(plain.faces)
    # the chordal bound, the angle bound (excepted trim corners aside) and the median
    err = chordal_errors(surf, r.points[r.faces], r.uv[r.faces])
    assert err.max() <= eps * (1 + 1e-9)
    ang = min_angles(r.points, r.faces)
    others = np.setdiff1d(np.arange(len(r.faces)), r.corner_triangles)
    assert ang[others].min() >= 30.0
    assert np.median(ang) >= 48.0
    # the border is untouched: same border vertices, same boundary loops, seams welded
    assert np.array_equal(np.sort(r.points[r.border_vertices], axis=0),
                          np.sort(plain.points[plain.border_vertices], axis=0))
    assert topology(r.mesh.faces).boundary_loops == topology(plain.mesh.faces).boundary_loops
    # every parameter triangle counter-clockwise
    T = r.uv[r.faces]
    area = (T[:, 1, 0] - T[:, 0, 0]) * (T[:, 2, 1] - T[:, 0, 1]) - (T[:, 1, 1] - T[:, 0, 1]) * (T[:, 2, 0] - T[:, 0, 0])
    assert (area > 0).all()


def test_a_pass_that_costs_the_median_is_undone():
    spec = load_spec(demo("dome", "hybrid").path)
    base = replace(spec.params(), max_edge=None, chord_arc=0.0, max_deviation=1e-3 * spec.model.surface.size)
    plain = mesh_hybrid(spec.model, replace(base, coarsen_angle=0.0))
    strict = mesh_hybrid(spec.model, replace(base, median_floor=60.0))  # no mesh has a median of 60
    assert strict.collapses == 0
    assert np.array_equal(strict.faces, plain.faces) and np.allclose(strict.points, plain.points)


def test_coarsening_respects_max_edge():
    spec = load_spec(demo("bezier-hole", "hybrid").path)
    h = 0.15
    r = mesh_hybrid(spec.model, replace(spec.params(), max_edge=h, chord_arc=0.0, max_deviation=None))
    e = r.points[r.faces][:, [1, 2, 0]] - r.points[r.faces]
    assert np.sqrt((e * e).sum(-1)).max() <= h * (1 + 1e-9)
    assert r.collapses > 0


def test_coarsen_angle_is_validated():
    with pytest.raises(ValueError, match="coarsen_angle"):
        HybridParams(coarsen_angle=20.0)  # below min_angle 30
    with pytest.raises(ValueError, match="coarsen_angle"):
        HybridParams(coarsen_angle=61.0)
    HybridParams(coarsen_angle=0.0)  # off

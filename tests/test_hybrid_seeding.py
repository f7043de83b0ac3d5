"""Seeding Stage III along lines of curvature (seeding.py)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from algorithms.demos import demo
from algorithms.hybrid import surfaces as S
from algorithms.hybrid.chordal import chordal_errors
from algorithms.hybrid.mesher import mesh_hybrid
from algorithms.hybrid.model import HybridModel
from algorithms.hybrid.seeding import BASE_ANGLE, FILL, principal_lattice, seed_points
from algorithms.hybrid.spec import load_spec
from algorithms.metrics import min_angles


def test_the_lattice_follows_the_rulings_of_a_cylinder_and_is_sized_by_the_tolerance():
    R, eps = 2.0, 1e-3
    model = HybridModel("cyl", S.cylinder(R, 0.0, 3.0))
    P, h = principal_lattice(model, eps)
    assert len(P)
    # columns at constant v (the rulings), an even number of them round the seam
    cols = np.unique(np.round(P[:, 1], 9))
    assert len(cols) % 2 == 0
    # the columns' spacing w across: kappa w^2 / 8 = FILL eps at most (kappa = 1 / R), and close to it
    w = R * (cols[1] - cols[0])
    assert 1 / R * w * w / 8 <= FILL * eps * (1 + 1e-9)
    assert 1 / R * w * w / 8 > 0.9 * FILL * eps
    assert h == pytest.approx(w, rel=1e-6)
    # along a column: 2 w / tan(BASE_ANGLE)
    rows = np.sort(P[np.isclose(P[:, 1], cols[0]), 0])
    assert np.allclose(np.diff(rows), 2 * w / math.tan(math.radians(BASE_ANGLE)), rtol=1e-3)


@pytest.mark.parametrize("surface", [
    S.sphere(1.0, -1.0, 1.0),  # curved along both families: no straight columns
    S.from_functions(lambda u, v: u, lambda u, v: v, lambda u, v: 0.1 * u * v, (0.0, 1.0, 0.0, 1.0)),  # twisted
])
def test_no_lattice_where_the_parameter_lines_are_not_straight_lines_of_curvature(surface):
    P, _ = principal_lattice(HybridModel("s", surface), 1e-3)
    assert len(P) == 0


def test_bezier_patches_are_not_seeded():
    for name in ("bezier-hole", "dome"):
        spec = load_spec(demo(name, "hybrid").path)
        lattice, h = principal_lattice(spec.model, 1e-3 * spec.model.surface.size)
        assert len(lattice) == 0 and len(seed_points(spec.model, lattice, h, np.zeros((0, 2, 2)))) == 0


def test_seeded_interstage_keeps_every_bound_with_fewer_triangles():
    spec = load_spec(demo("interstage", "hybrid").path)
    surf = spec.model.surface
    eps = 2.5e-4 * surf.size
    base = replace(spec.params(), max_edge=None, chord_arc=0.0, max_deviation=eps, coarsen_angle=0.0)
    plain = mesh_hybrid(spec.model, replace(base, seed=False))
    r = mesh_hybrid(spec.model, base)
    assert r.seeded > 500 and plain.seeded == 0
    assert len(r.faces) < 0.85 * len(plain.faces)
    err = chordal_errors(surf, r.points[r.faces], r.uv[r.faces])
    assert err.max() <= eps * (1 + 1e-9)
    ang = min_angles(r.points, r.faces)
    others = np.setdiff1d(np.arange(len(r.faces)), r.corner_triangles)
    assert ang[others].min() >= 30.0 and np.median(ang) >= 50.0
    assert r.topology.boundary_loops == plain.topology.boundary_loops == 12


def test_the_lattice_keeps_max_edge():
    model = HybridModel("cyl", S.cylinder(2.0, 0.0, 3.0))
    _, w_free = principal_lattice(model, 1e-3)
    P, w = principal_lattice(model, 1e-3, max_edge=0.5 * w_free)
    cols = np.unique(np.round(P[:, 1], 9))
    rows = np.sort(P[np.isclose(P[:, 1], cols[0]), 0])
    assert np.diff(rows).max() <= 0.5 * w_free * (1 + 1e-3)  # the column edge, the longest one
    assert w < 0.5 * w_free

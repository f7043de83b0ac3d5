"""The curvature criterion in chordal form (max_deviation), the root finder, and the size control."""

import math
from dataclasses import replace

import numpy as np
import pytest

from algorithms.demos import demo
from algorithms.hybrid import surfaces as S
from algorithms.hybrid.chordal import chordal_errors
from algorithms.hybrid.mesher import mesh_hybrid
from algorithms.hybrid.model import HybridModel
from algorithms.hybrid.rfunctions import r_and
from algorithms.hybrid.spec import load_spec
from algorithms.topology import boundary_loops


def chordal_params(name, eps_rel):
    spec = load_spec(demo(name, "hybrid").path)
    p = replace(spec.params(), max_edge=None, chord_arc=0.0, border_chord_arc=0.0,
                max_deviation=eps_rel * spec.model.surface.size)
    return spec, p


def closest_distance(surface, q, uv0):
    """Brute-force check: the distance from points q to the surface, Gauss-Newton from uv0 (many steps)."""
    a, b, c, d = surface.domain
    u, v = uv0[:, 0].copy(), uv0[:, 1].copy()
    for _ in range(30):
        R = surface(u, v)
        ru, rv = surface.derivatives(u, v)
        r = R - q
        a11, a12, a22 = (ru * ru).sum(1), (ru * rv).sum(1), (rv * rv).sum(1)
        g1, g2 = (ru * r).sum(1), (rv * r).sum(1)
        det = a11 * a22 - a12 * a12
        u = np.clip(u - (a22 * g1 - a12 * g2) / det, a, b)
        v = np.clip(v - (a11 * g2 - a12 * g1) / det, c, d)
    return np.linalg.norm(surface(u, v) - q, axis=1)


def test_chordal_error_of_a_chord_across_a_cylinder_is_its_sagitta():
    R = 2.0
    cyl = S.cylinder(R, 0.0, 1.0)
    th = 0.3  # the triangle spans th radians around the axis; one edge along the axis
    uv = np.array([[[0.0, 0.0], [0.0, th], [0.5, 0.0]]])
    T3 = cyl(uv[..., 0], uv[..., 1])
    err = chordal_errors(cyl, T3, uv)[0]
    assert err == pytest.approx(R * (1 - np.cos(th / 2)), rel=1e-6)  # the edge across: sagitta
    # along a generator only: a straight edge on the surface, no error
    uv2 = np.array([[[0.0, 0.0], [1.0, 0.0], [0.5, 1e-9]]])
    assert chordal_errors(cyl, cyl(uv2[..., 0], uv2[..., 1]), uv2)[0] < 1e-12


@pytest.mark.parametrize("name", ["bezier-hole", "dome"])
def test_max_deviation_bounds_the_chordal_error_and_keeps_30_degrees(name):
    spec, p = chordal_params(name, 1e-3)
    r = mesh_hybrid(spec.model, p)
    assert r.stats_excluding_corners.min >= 30
    assert r.stats_after.median >= 48
    T = r.points[r.faces]
    q = np.vstack([T.mean(1), 0.5 * (T[:, 0] + T[:, 1]), 0.5 * (T[:, 1] + T[:, 2]), 0.5 * (T[:, 2] + T[:, 0])])
    U = r.uv[r.faces]
    uq = np.vstack([U.mean(1), 0.5 * (U[:, 0] + U[:, 1]), 0.5 * (U[:, 1] + U[:, 2]), 0.5 * (U[:, 2] + U[:, 0])])
    dist = closest_distance(spec.model.surface, q, uq)
    assert dist.max() <= 1.02 * p.max_deviation
    assert dist.max() > 0.3 * p.max_deviation  # the tolerance is what sized the mesh


def test_chordal_criterion_grades_the_mesh_by_curvature():
    # the paper's patch is a cylinder over the profile (12u(1-u), y(u)): curvature 0.083 at u = 0 and 1,
    # 2.67 at u = 0.5 (32 times more); h ∝ 1/√κ makes the edges there about 5.7 times shorter
    spec, p = chordal_params("bezier-hole", 5e-4)
    r = mesh_hybrid(spec.model, p)
    e = np.vstack([r.faces[:, [0, 1]], r.faces[:, [1, 2]], r.faces[:, [2, 0]]])
    L = np.linalg.norm(r.points[e[:, 0]] - r.points[e[:, 1]], axis=1)
    um = r.uv[e].mean(axis=1)[:, 0]
    flat = np.median(L[(um < 0.08) | (um > 0.92)])
    curved = np.median(L[np.abs(um - 0.5) < 0.05])
    assert 3.0 < flat / curved < 9.0


def test_size_control_reaches_a_thousand_triangles_with_the_openings():
    spec, p = chordal_params("interstage", 3e-3)
    r = mesh_hybrid(spec.model, p)
    assert 700 < len(r.faces) < 1500
    assert r.stats_excluding_corners.min >= 30
    assert len(boundary_loops(r.mesh.faces)) == 12  # every opening and both rims, seam welded
    assert r.max_border_distance < 1e-8 * spec.model.surface.size


def test_root_finder_is_exact_on_a_circle_and_at_a_kink():
    flat = S.from_functions(lambda u, v: u, lambda u, v: v, lambda u, v: 0 * u, (-1.0, 1.0, -1.0, 1.0))
    m = HybridModel("disk", flat, lambda x, y, z: 0.16 - x * x - y * y)
    rng = np.random.default_rng(3)
    ang = rng.uniform(0, 2 * np.pi, 50)
    p = np.zeros((50, 2))
    q = 0.9 * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    x = m.bisect(p, q)
    assert np.abs(np.hypot(x[:, 0], x[:, 1]) - 0.4).max() < 1e-14
    # a kink at the root: r_and(a, a) = (2 - √2) a for a > 0 and (2 + √2) a for a < 0 (a = 0.3 - x)
    m2 = HybridModel("kink", flat, lambda x, y, z: r_and(0.3 - x, 0.3 - x))
    x2 = m2.bisect(np.array([[0.0, 0.1]]), np.array([[0.9, 0.1]]))
    assert abs(x2[0, 0] - 0.3) < 1e-13


def test_border_tolerance_alone_changes_only_the_border_resolution():
    spec, p = chordal_params("interstage", 4e-4)
    tied = mesh_hybrid(spec.model, p)
    loose = mesh_hybrid(spec.model, replace(p, border_deviation=math.inf))
    # the border curve is no longer cut to the chordal tolerance: fewer border vertices and triangles,
    # the surface still within it and every opening still there
    assert len(loose.border_vertices) < 0.8 * len(tied.border_vertices)
    assert len(loose.faces) < len(tied.faces)
    for r in (tied, loose):
        assert r.stats_excluding_corners.min >= 30
        assert len(boundary_loops(r.mesh.faces)) == 12
        T, U = r.points[r.faces], r.uv[r.faces]
        assert chordal_errors(spec.model.surface, T, U).max() <= p.max_deviation * (1 + 1e-9)


def test_cli_max_deviation(tmp_path):
    import json

    from algorithms.cli import main

    out, rep = tmp_path / "m.ply", tmp_path / "r.json"
    assert main(["hybrid", "--demo", "bezier-hole", "-o", str(out), "--max-deviation", "0.01",
                 "--max-edge", "100", "--chord-arc", "0", "--report", str(rep)]) == 0
    d = json.loads(rep.read_text())
    assert d["params"]["max_deviation"] == 0.01 and d["params"]["border_deviation"] is None
    assert d["angles_after_excluding_corners"]["min"] >= 30
    assert 150 < d["counts"]["triangles_final"] < 1500


def test_cli_coarsen_angle(tmp_path):
    import json

    from algorithms.cli import main

    counts = {}
    for a in ("0", "36"):
        out, rep = tmp_path / f"m{a}.ply", tmp_path / f"r{a}.json"
        assert main(["hybrid", "--demo", "bezier-hole", "-o", str(out), "--max-deviation", "0.002",
                     "--chord-arc", "0", "--coarsen-angle", a, "--report", str(rep)]) == 0
        d = json.loads(rep.read_text())
        assert d["params"]["coarsen_angle"] == float(a)
        assert d["angles_after_excluding_corners"]["min"] >= 30
        counts[a] = (d["counts"]["triangles_final"], d["counts"]["collapses"])
    assert counts["0"][1] == 0 and counts["36"][1] > 0
    assert counts["36"][0] < counts["0"][0]

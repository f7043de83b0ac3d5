"""Free points (eq. 4): q2 shortens along a line of free points; grid and k-d tree agree; PRAF."""

import numpy as np
import pytest

from algorithms.bridges import bridge_factors, find_candidate_bridges
from algorithms.cases import combine, disk
from algorithms.field.free_points import free_points, praf_normal, praf_potential, q2_many
from algorithms.field.quality import g0, q2_segment
from algorithms.mesh import Icadm
from algorithms.params import FieldParams


def gap_points(n=7):
    return np.stack([np.linspace(1.05, 1.55, n), np.zeros(n), np.zeros(n)], 1)


def test_line_of_free_points_shortens_q2():
    a, b = np.array([1.0, 0, 0]), np.array([1.6, 0, 0])
    L = 0.6
    q2 = q2_segment(a, b, gap_points(), kt=0.5, rc=0.15)
    assert q2 < 0.75 * L
    assert q2_segment(a, b, np.zeros((0, 3)), kt=0.5, rc=0.15) == pytest.approx(L)
    # points far from the segment do nothing
    assert q2_segment(a, b, gap_points() + [0, 5, 0], kt=0.5, rc=0.15) == pytest.approx(L)
    # more trust in the free points shortens more
    assert q2_segment(a, b, gap_points(), kt=0.9, rc=0.15) < q2
    p_full, p_light = FieldParams(mode="full", kt=0.5, rc_factor=0.25), FieldParams(mode="light")
    tau_a, tau_b, n = [0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0]
    f_full = bridge_factors(a, tau_a, n, b, tau_b, n, p_full, gap_points(), lc=0.6)
    f_light = bridge_factors(a, tau_a, n, b, tau_b, n, p_light, gap_points(), lc=0.6)
    assert f_light.q2 == pytest.approx(L) and f_light.q12 == pytest.approx(f_light.q1)
    assert f_full.q2 < 0.75 * L and f_full.q12 > f_full.q1 and f_full.Q > f_light.Q


def test_grid_q2_agrees_with_kdtree_q2():
    rng = np.random.default_rng(2)
    pts = rng.uniform(-1, 1, size=(200, 3))
    fp = free_points(pts, kt=0.6, rc=0.2)
    x, o = rng.uniform(-1, 1, size=(20, 3)), rng.uniform(-1, 1, size=(20, 3))
    got = q2_many(fp, x, o, exact=True)
    ref = [q2_segment(x[i], o[i], pts, kt=0.6, rc=0.2, samples=8) for i in range(20)]
    np.testing.assert_allclose(got, ref, rtol=1e-3)  # same midpoint rule; the grid cuts off at G < 1e-4 G(0)
    # the lattice of the field kernel: trilinear interpolation of sum G, 16 samples
    lat = q2_many(fp, x, o)
    ref16 = [q2_segment(x[i], o[i], pts, kt=0.6, rc=0.2, samples=16) for i in range(20)]
    np.testing.assert_allclose(lat, ref16, rtol=0.03)
    L = np.linalg.norm(o - x, axis=1)
    assert np.all(lat < L) and np.all(lat > 0)


def test_praf_potential_and_normal():
    rng = np.random.default_rng(4)
    xy = rng.uniform(-1, 1, size=(300, 2))
    pts = np.column_stack([xy, 0.01 * rng.normal(size=300)])
    fp = free_points(pts, kt=0.5, rc=0.2)
    assert praf_potential(fp, [[0.0, 0, 0]])[0] > g0(0.5)
    assert praf_potential(fp, [[0.0, 0, 5.0]])[0] == 0.0
    n = praf_normal(fp, np.array([0.1, 0.1, 0.0]))
    assert abs(n[2]) > 0.99


def test_free_points_raise_the_bridge_quality_in_full_mode():
    m = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    plain = find_candidate_bridges(Icadm(m), FieldParams(mode="full", lc=0.6))
    with_fp = find_candidate_bridges(Icadm(m, free_points=gap_points(9)), FieldParams(mode="full", lc=0.6))
    qa = max(c.quality for c in plain.arrived())
    qb = max(c.quality for c in with_fp.arrived())
    assert qb > qa


def test_capped_q2_is_exact_below_the_cap_and_certain_above_it():
    """The field kernel's q2 stops once the partial sum passes the pruning cap (4)."""
    from algorithms.field.free_points import lattice_args, q2_lattice, q2_lattice_capped

    rng = np.random.default_rng(5)
    fp = free_points(rng.uniform(-1, 1, size=(200, 3)), kt=0.6, rc=0.2)
    la = lattice_args(fp)
    for _ in range(40):
        x, o = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
        L = float(np.linalg.norm(o - x))
        q = q2_lattice(x, o, L, *la)
        for cap in (0.3 * q, 0.9 * q, 1.1 * q, 1e300):
            c = q2_lattice_capped(x, o, L, *la, cap)
            if cap >= q:
                assert c == pytest.approx(q, rel=1e-12)
            else:
                assert cap < c <= q * (1 + 1e-12)


def test_one_free_point():
    """A single free point (a cut that leaves one loose vertex) builds its field like many do: the
    k-d tree query for one neighbour returns flat arrays (full mode crashed on it)."""
    fp = free_points(np.array([[0.0, 0.0, 0.0]]), kt=0.5, rc=0.2)
    assert praf_potential(fp, [[0.0, 0, 0]])[0] == pytest.approx(g0(0.5), rel=1e-6)
    assert praf_potential(fp, [[0.0, 0, 5.0]])[0] == 0.0
    x, o = np.array([[-0.3, 0.0, 0.0]]), np.array([[0.3, 0.0, 0.0]])
    ref = q2_segment(x[0], o[0], fp.points, kt=0.5, rc=0.2, samples=8)
    np.testing.assert_allclose(q2_many(fp, x, o, exact=True), [ref], rtol=1e-3)
    assert ref < 0.6


@pytest.mark.parametrize("rc", [0.0, -1.0, float("nan")])
def test_a_radius_that_is_not_positive_is_refused_clearly(rc):
    # r_c = 0 came from L_c = 0 (islands touching at a vertex) and ended in a numpy error deep inside
    with pytest.raises(ValueError, match="r_c must be a positive number"):
        free_points(np.zeros((4, 3)), kt=1.0, rc=rc)

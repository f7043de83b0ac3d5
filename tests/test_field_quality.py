"""Bridge quality, eqs. 1-10 (spec/repair.md §3): worked examples and the limits of each factor."""

import numpy as np
import pytest

from algorithms.bridges import bridge_factors
from algorithms.field.quality import basic_task, free_point_g, g0, log_q1, q1, q3, q_topological
from algorithms.params import FieldParams


def test_worked_example_two_coplanar_disks_qT_is_one():
    # disk 1 at the origin, disk 2 centred at (4, 0, 0), both normal +z (spec §3)
    a, tau_a = np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    b, tau_b = np.array([3.0, 0, 0]), np.array([0.0, -1, 0])
    assert q_topological(a, tau_a, b, tau_b) == pytest.approx(1.0)
    f = bridge_factors(a, tau_a, [0, 0, 1], b, tau_b, [0, 0, 1], FieldParams(), lc=2.0)
    assert f.qT == pytest.approx(1.0)
    assert f.q3 == pytest.approx(1.0)  # n_X = s_A is perpendicular to d
    assert f.q4 == pytest.approx(1.0)  # s_B = (0, 0, 1) = n_B: a tangential continuation
    assert f.q1 == pytest.approx(np.exp(-1.0))
    assert f.Q == pytest.approx(1.0 * np.exp(-1.0) * 1.0 * (1 + 1.0))


def test_worked_example_flipped_disk_qT_is_minus_one():
    a, tau_a = np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    b, tau_b = np.array([3.0, 0, 0]), np.array([0.0, 1, 0])  # disk 2 flipped: normal -z
    assert q_topological(a, tau_a, b, tau_b) == pytest.approx(-1.0)
    f = bridge_factors(a, tau_a, [0, 0, 1], b, tau_b, [0, 0, -1], FieldParams(), lc=2.0)
    assert f.qT == pytest.approx(-1.0) and f.Q < 0


@pytest.mark.parametrize("kernel", ["gauss", "cauchy"])
def test_q1_limits(kernel):
    L = np.linspace(0, 50, 2001)
    v = q1(L, 0.7, kernel)
    assert v[0] == 1.0
    assert np.all(np.diff(v) <= 0) and np.all(v >= 0)
    assert q1(1e6, 0.7, kernel) < 1e-9


@pytest.mark.parametrize("kernel", ["gauss", "cauchy"])
def test_free_point_g_limits(kernel):
    for kt in (0.1, 0.5, 0.9):
        assert free_point_g(0.0, kt, 0.3, kernel) == pytest.approx(kt / (1 - kt)) == pytest.approx(g0(kt))
    r = np.linspace(0, 10, 500)
    assert np.all(np.diff(free_point_g(r, 0.5, 0.3, kernel)) <= 0)


def test_q3_zero_when_normal_parallel_to_d():
    d = np.array([0.0, 0.6, 0.8])
    assert q3(d, d) == pytest.approx(0.0)
    assert q3(-d, d) == pytest.approx(0.0)
    assert q3(np.array([1.0, 0, 0]), d) == pytest.approx(1.0)


def test_eq10_equals_eq9_for_random_inputs():
    rng = np.random.default_rng(3)
    p = FieldParams(ki=0.7)
    for _ in range(50):
        x, o = rng.normal(size=3), rng.normal(size=3)
        n_x = rng.normal(size=3)
        n_x /= np.linalg.norm(n_x)
        tau = rng.normal(size=3)
        tau /= np.linalg.norm(tau)
        n_o = np.cross(tau, rng.normal(size=3))
        n_o /= np.linalg.norm(n_o)
        f = basic_task(x, n_x, o, tau, n_o, p, 0.9)
        assert f["Q"] == pytest.approx(f["Q10"], abs=1e-12)  # (9) == (10): q_T q3 = n_X . s_O
        assert 0 <= f["q4"] <= 1 and 0 <= f["q3"] <= 1 + 1e-12


def test_ki_favours_the_tangential_continuation():
    # A on disk 1; B1 continues the plane (q4 = 1), B2 leaves at 60 degrees (q4 < 1)
    a, tau_a, n_a = np.array([1.0, 0, 0]), np.array([0.0, 1, 0]), np.array([0.0, 0, 1])
    b1, tau_b1, n_b1 = np.array([1.6, 0, 0]), np.array([0.0, -1, 0]), np.array([0.0, 0, 1])
    ang = np.radians(60)
    n_b2 = np.array([-np.sin(ang), 0, np.cos(ang)])  # the target island tilted about the y axis
    b2, tau_b2 = np.array([1.6, 0, 0]), np.array([0.0, -1, 0])
    ratios = []
    for ki in (0.0, 1.0, 4.0):
        p = FieldParams(ki=ki)
        q_tan = bridge_factors(a, tau_a, n_a, b1, tau_b1, n_b1, p, lc=0.6)
        q_ang = bridge_factors(a, tau_a, n_a, b2, tau_b2, n_b2, p, lc=0.6)
        assert q_tan.q4 == pytest.approx(1.0) and q_ang.q4 < 0.9
        ratios.append(q_tan.Q / q_ang.Q)
    assert ratios[0] == pytest.approx(1.0)  # k_i = 0 ignores the continuation
    assert ratios[0] < ratios[1] < ratios[2]


@pytest.mark.parametrize("kernel", ["gauss", "cauchy"])
def test_log_q1_is_the_log_of_q1_and_still_orders_where_q1_underflows(kernel):
    L = np.linspace(0, 5, 101)
    assert np.allclose(log_q1(L, 0.7, kernel), np.log(q1(L, 0.7, kernel)))
    far = np.array([40.0, 50.0, 60.0]) * 0.7
    if kernel == "gauss":
        assert np.all(q1(far, 0.7, kernel) == 0.0)  # exp(-1600) underflows
    assert np.all(np.diff(log_q1(far, 0.7, kernel)) < 0)


def test_straight_bridge_with_every_pair_far_beyond_lc_is_the_shortest_compatible():
    """Two parallel rows of border points walked in opposite directions (a band between two rims),
    L_c a thousandth of their gap: every q1 underflows to 0, and the best pair must still be a
    shortest one (a rung of the band), not the first pair of the matrix."""
    from algorithms.repair import _best_straight_bridge

    x = np.linspace(0.0, 1.0, 11)
    pa = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1)
    pb = np.stack([x[::-1], np.full_like(x, 0.1), np.zeros_like(x)], axis=1)
    ta, tb = np.tile([1.0, 0, 0], (11, 1)), np.tile([-1.0, 0, 0], (11, 1))
    na = np.tile([0.0, -1, 0], (11, 1))  # the surface continues away from the band at A
    i, j, q = _best_straight_bridge(pa, ta, na, pb, tb, lc=1e-4, ki=1.0)
    assert np.linalg.norm(pa[i] - pb[j]) == pytest.approx(0.1)
    assert q == 0.0  # exp(-(0.1 / 1e-4)^2): the quality itself does underflow

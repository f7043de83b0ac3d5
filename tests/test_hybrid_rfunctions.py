"""R-functions (spec/hybrid.md §1, eq. (2), (3)): identities and signs."""

import numpy as np
import pytest

from algorithms.hybrid.rfunctions import (
    circle_z,
    crossing_cylinders,
    r_and,
    r_not,
    r_or,
    rect,
    rot_x,
    rot_z,
    srect,
)

rng = np.random.default_rng(6)
X = rng.normal(size=2000) * 3
Y = rng.normal(size=2000) * 3


def test_signs_follow_min_and_max():
    assert np.array_equal(np.sign(r_and(X, Y)), np.sign(np.minimum(X, Y)))
    assert np.array_equal(np.sign(r_or(X, Y)), np.sign(np.maximum(X, Y)))
    assert np.array_equal(r_not(X), -X)


def test_identities():
    # De Morgan holds exactly for system (3); commutativity; x ∧ 0 = x - |x|, x ∨ 0 = x + |x|
    assert np.allclose(r_not(r_and(X, Y)), r_or(r_not(X), r_not(Y)), atol=1e-12)
    assert np.allclose(r_and(X, Y), r_and(Y, X))
    assert np.allclose(r_or(X, Y), r_or(Y, X))
    assert np.allclose(r_and(X, 0 * X), X - np.abs(X))
    assert np.allclose(r_or(X, 0 * X), X + np.abs(X))
    # worked values: 3 ∧ 4 = 3 + 4 - 5 = 2, 3 ∨ 4 = 12, (-3) ∧ 4 = -4
    assert r_and(3.0, 4.0) == pytest.approx(2.0)
    assert r_or(3.0, 4.0) == pytest.approx(12.0)
    assert r_and(-3.0, 4.0) == pytest.approx(-4.0)
    # n-ary folds
    assert r_and(1.0, 2.0, 3.0) == pytest.approx(r_and(r_and(1.0, 2.0), 3.0))


def test_primitives_signs():
    assert circle_z(0.0, 0.0, 1.0) == 1.0 and circle_z(2.0, 0.0, 1.0) < 0 and circle_z(0.6, 0.8, 1.0) == pytest.approx(0)
    assert rect(0.0, 0.0, 2.0, 1.0) > 0 and rect(0.9, 0.4, 2.0, 1.0) > 0
    assert rect(1.1, 0.0, 2.0, 1.0) < 0 and rect(0.0, 0.6, 2.0, 1.0) < 0
    assert rect(1.0, 0.2, 2.0, 1.0) == pytest.approx(0, abs=1e-12)
    # rounded rectangle: the sharp corner is cut away, the rounded corner's arc is the border
    w, h, r = 2.0, 1.0, 0.3
    assert srect(0.0, 0.0, w, h, r) > 0
    assert srect(0.99, 0.49, w, h, r) < 0  # near the sharp corner: outside
    cx, cy = w / 2 - r, h / 2 - r
    t = np.linspace(0.05, np.pi / 2 - 0.05, 9)
    assert np.allclose(srect(cx + r * np.cos(t), cy + r * np.sin(t), w, h, r), 0, atol=1e-12)
    assert np.all(srect(cx + 0.9 * r * np.cos(t), cy + 0.9 * r * np.sin(t), w, h, r) > 0)


def test_rotations_and_f1():
    a = 0.7
    x, z = rot_x(X, Y, a), rot_z(X, Y, a)
    assert np.allclose(x * x + z * z, X * X + Y * Y)
    assert np.allclose(rot_x(x, z, -a), X) and np.allclose(rot_z(x, z, -a), Y)
    # f1 > 0 outside both cylinders, < 0 inside either
    assert crossing_cylinders(0.0, 0.0, 2.0, 0.5, 0.4) > 0
    assert crossing_cylinders(5.0, 0.1, 0.1, 0.5, 0.4) < 0  # inside the cylinder along Ox
    assert crossing_cylinders(0.1, 5.0, 0.1, 0.5, 0.4) < 0  # inside the cylinder along Oy

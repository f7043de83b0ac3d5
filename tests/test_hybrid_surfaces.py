"""Parametric surfaces: Bezier (8) against de Casteljau, the cone (9), periodic closure."""

import math

import numpy as np
import pytest

from algorithms.hybrid.surfaces import PAPER_BEZIER, bezier, cone, cylinder, de_casteljau, sphere, torus


@pytest.mark.parametrize("shape", [(4, 4), (2, 5), (6, 3), (2, 2)])
def test_bezier_matches_de_casteljau(shape):
    rng = np.random.default_rng(sum(shape))
    P = rng.normal(size=shape + (3,))
    s = bezier(P)
    uv = rng.random((50, 2))
    got = s(uv[:, 0], uv[:, 1])
    want = np.array([de_casteljau(P, u, v) for u, v in uv])
    assert np.allclose(got, want, atol=1e-12)
    # corners interpolate the corner control points
    assert np.allclose(s(0.0, 0.0), P[0, 0]) and np.allclose(s(1.0, 1.0), P[-1, -1])


def test_paper_patch_is_developable_form():
    # spec: the paper's patch is R = (12 u (1 - u), y(u), z(v))
    s = bezier(PAPER_BEZIER)
    u, v = np.meshgrid(np.linspace(0, 1, 7), np.linspace(0, 1, 5), indexing="ij")
    p = s(u, v)
    assert np.allclose(p[..., 0], 12 * u * (1 - u))
    assert np.allclose(p[:, :1, 1], p[:, :, 1])  # y depends on u only
    assert np.allclose(p[:1, :, 2], p[:, :, 2])  # z depends on v only


def test_cone_formula_and_periodic_closure():
    c = cone(2.0, 1.0, 4.0, v0=0.3)
    u = np.linspace(0, 4, 9)
    a, b, cc, d = c.domain
    assert d - cc == pytest.approx(2 * math.pi) and c.periodic_v and not c.periodic_u
    p = c(u, np.full_like(u, 0.3))
    r = 2.0 + (1.0 - 2.0) * u / 4.0  # (9)
    assert np.allclose(p, np.stack([r * math.cos(0.3), u, r * math.sin(0.3)], axis=-1))
    assert np.allclose(c(u, np.full_like(u, cc)), c(u, np.full_like(u, d)))
    for s in (cylinder(1.0, 0, 1), torus(2.0, 0.5), sphere(1.0, -1.0, 1.0)):
        a, b, cc, d = s.domain
        v = np.linspace(a, b, 5)
        assert np.allclose(s(v, np.full_like(v, cc)), s(v, np.full_like(v, d)))
    t = torus(2.0, 0.5)
    w = np.linspace(0, 6, 5)
    assert t.periodic_u and np.allclose(t(np.full_like(w, 0.0), w), t(np.full_like(w, 2 * math.pi), w))


def test_bad_inputs_name_the_parameter():
    with pytest.raises(ValueError, match="control"):
        bezier(np.zeros((1, 3, 3)))
    with pytest.raises(ValueError, match="torus"):
        torus(1.0, 2.0)

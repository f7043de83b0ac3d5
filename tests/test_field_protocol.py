"""The missing-surface field interface (§8): BIAF, PRAF, composite; tracers work through it."""

import numpy as np
import pytest

from algorithms.boundary import loop_frames
from algorithms.cases import combine, disk
from algorithms.field.free_points import free_points
from algorithms.field.indicator import IndicatorField, sources_from_frames
from algorithms.field.protocol import Biaf, Composite, MissingSurfaceField, Praf
from algorithms.force_lines import make_targets, trace
from algorithms.params import FieldParams


@pytest.fixture(scope="module")
def biaf():
    m = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    src = sources_from_frames([f for f in loop_frames(m) if f.island == 1])
    return Biaf(IndicatorField(src, FieldParams(), 0.6)), src


def test_biaf_answers_every_index(biaf):
    f, _ = biaf
    assert isinstance(f, MissingSurfaceField)
    s = f.sample(np.array([1.2, 0, 0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]))
    assert s.potential == pytest.approx(s.tension) and s.tension > 0
    assert s.force[0] > 0  # attracted towards disk B
    assert f.potential(np.array([1.2, 0, 0]), np.array([1.0, 0, 0])) == pytest.approx(s.potential)
    # Omega: positive when the force points along the outward direction, 0 against it
    x, tau = np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    assert f.attraction(x, tau, np.array([0, 0, 1.0]), np.array([1.0, 0, 0])) > 0
    assert f.attraction(x, tau, np.array([0, 0, 1.0]), np.array([-1.0, 0, 0])) == 0.0


def test_composite_of_one_member_is_that_member(biaf):
    f, _ = biaf
    c = Composite([(2.0, f)])
    x, t, h = np.array([1.3, 0.1, 0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    a, b = f.sample(x, t, h), c.sample(x, t, h)
    np.testing.assert_allclose(b.force, 2 * a.force)
    np.testing.assert_allclose(b.normal, a.normal, atol=1e-12)
    assert b.potential == pytest.approx(2 * a.potential)


def test_composite_needs_every_index_and_adds_praf(biaf):
    f, _ = biaf
    pts = np.stack([np.linspace(1.05, 1.55, 9), np.zeros(9), np.zeros(9)], 1)
    pts = np.vstack([pts, pts + [0, 0.05, 0], pts - [0, 0.05, 0]])
    praf = Praf(free_points(pts, kt=0.5, rc=0.15))
    with pytest.raises(ValueError, match="provides"):
        Composite([(1.0, praf)])  # PRAF alone gives no force
    c = Composite([(1.0, f), (0.5, praf)])
    x, t, h = np.array([1.3, 0.0, 0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    s = c.sample(x, t, h)
    assert s.potential > f.sample(x, t, h).potential
    assert abs(s.normal[2]) > 0.99 and abs(s.normal @ t) < 1e-12


def test_tracer_runs_on_a_composite_field(biaf):
    f, src = biaf
    pts = np.stack([np.linspace(1.05, 1.55, 9), np.zeros(9), np.zeros(9)], 1)
    c = Composite([(1.0, f), (0.3, Praf(free_points(pts, kt=0.5, rc=0.15)))])
    tg = make_targets(src.points, np.full(len(src), 0.1), 0.05, vertex=src.vertex, island=src.island)
    ln = trace(c, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), FieldParams(), tg, step=0.05)
    assert ln.arrived and ln.end_island == 1

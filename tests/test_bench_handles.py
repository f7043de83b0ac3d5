"""bench.handles, the sweep's handle finder: a greedy homology basis of a closed mesh."""

import numpy as np
import pytest
import trimesh

from bench.handles import homology_cycles


def test_a_torus_has_its_meridian_and_one_longitude_through_the_root():
    """Torus R = 1, r = 0.3 rooted on its outer equator: 2 cycles (genus 1); the shorter is the
    meridian through the root, 2 pi r (within the polygon's 1 %), the other goes round the hole,
    longer than the inner equator 2 pi (R - r) and shorter than the outer one 2 pi (R + r)."""
    t = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3, major_sections=96, minor_sections=48)
    V, F = np.asarray(t.vertices), np.asarray(t.faces)
    cycles = homology_cycles(V, F, int(np.argmax(V[:, 0])))
    assert len(cycles) == 2
    assert cycles[0].length == pytest.approx(2 * np.pi * 0.3, rel=0.01)
    assert 2 * np.pi * 0.7 < cycles[1].length < 2 * np.pi * 1.3
    a, b = cycles[0].edge
    assert abs(V[a] - V[b]).sum() > 0 and {a, b} <= set(np.unique(F).tolist())


def test_a_sphere_has_no_cycle_and_a_double_torus_four():
    from bench.sweep import make_cut

    s = trimesh.creation.icosphere(3)
    assert homology_cycles(s.vertices, s.faces, 0) == []
    truth = make_cut("frep-dtorus", 1, 0).truth
    assert len(homology_cycles(truth.vertices, truth.faces, 0)) == 4


def test_an_open_mesh_is_refused():
    s = trimesh.creation.icosphere(2)
    with pytest.raises(ValueError, match="closed surface"):
        homology_cycles(s.vertices, s.faces[1:], 0)

"""bench.sweep's reading of a cut: the handles a cut takes whole (``hidden_handles``)."""

import numpy as np

from algorithms import cases as gen
from bench.cases import BenchCase, ball
from bench.sweep import cut_named, hidden_handles


def _case(truth, removed) -> BenchCase:
    c = gen.cut(truth, removed, name="t", description="", free_points=0, seed=1)
    return BenchCase("t", np.asarray(c.incomplete.vertices), np.asarray(c.incomplete.faces), np.zeros((0, 3)),
                     truth, 1, "")


def test_a_cut_across_a_tube_hides_no_handle_and_half_a_torus_one():
    """A torus (genus 1). A ball across its tube removes a band: the handle shows as two facing
    loops, none is hidden. The faces with x < 0.3 removed: a bent piece of tube (a cylinder, genus 0):
    none hidden either, the kept piece's two rims carry the handle. Everything removed but
    one disk (or two) of the tube's wall: the removed part is the torus less a disk, genus 1, and the
    input's one loop (or two) says nothing of the handle."""
    t = gen.torus(1.0, 0.3, 48, 16)
    c = t.vertices[t.faces].mean(axis=1)
    assert hidden_handles(_case(t, ball(t, np.array([1.3, 0.0, 0.0]), 0.4))) == 0
    assert hidden_handles(_case(t, c[:, 0] < 0.3)) == 0
    keep = ball(t, np.array([1.3, 0.0, 0.0]), 0.25)
    assert 0 < keep.sum() < len(t.faces) // 10
    assert hidden_handles(_case(t, ~keep)) == 1
    keep2 = keep | ball(t, np.array([-1.3, 0.0, 0.0]), 0.25)
    assert hidden_handles(_case(t, ~keep2)) == 1


def test_sweep_cuts_that_take_a_handle_whole():
    """flat-torus:25:1 (bench/sweep.py, a held-out seed): the cut removed a piece of the flat torus
    that holds its handle (genus 1); torus:1:0, a ball across the tube, hides none."""
    assert hidden_handles(cut_named("flat-torus:25:1")) == 1
    assert hidden_handles(cut_named("torus:1:0")) == 0

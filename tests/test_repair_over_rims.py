"""Lines between two loops that pass over a rim on their way (repair_field.over_a_rim): they cross
their own hole, pass over the strip of surface between it and the next hole, and cross that one.
They join the two holes across surface that is there, not across missing surface, and join
neither loop in the tunnel rule."""

from __future__ import annotations

import numpy as np
import pytest
from test_repair_random_cuts import closed_repair, sweep_model

import algorithms.repair_field as rf
from algorithms.metrics import topology
from algorithms.params import FieldParams
from algorithms.records import ARRIVED, ForceLine
from algorithms.repair import RepairParams, repair


def square(x0: float, x1: float, z: float = 0.0, n: int = 40) -> np.ndarray:
    """A closed square loop [x0, x1] x [0, 1] at height z, n points a side."""
    t = np.linspace(0.0, 1.0, n, endpoint=False)
    w = x1 - x0
    return np.vstack([np.c_[x0 + w * t, 0 * t, 0 * t + z], np.c_[x1 + 0 * t, t, 0 * t + z],
                      np.c_[x1 - w * t, 1 + 0 * t, 0 * t + z], np.c_[x0 + 0 * t, 1 - t, 0 * t + z]])


def line(points) -> ForceLine:
    P = np.asarray(points, dtype=np.float64)
    return ForceLine(P, np.zeros_like(P), np.zeros_like(P), np.zeros(len(P)), ARRIVED, 0, 0, 1, 0)


def test_a_line_across_two_holes_side_by_side_passes_over_the_strip_between_them():
    """Two unit holes 0.05 apart. A line from the left side of the first (x = 0) across it, over
    the strip (x 1-1.05) and across the second to its right side (x = 2.05): 0.025 from both rims
    at the strip (1.2 % of its length 2.05, within RIM_NEAR), after 0.5 from the first (more than
    RIM_AWAY times the floor, 2 % of the length): over a rim, read from either end. A line
    from the first hole's near side straight to the second's (across the strip only) and a line
    across a tube's gap (two rims 0.3 apart, one above the other) move away from one loop and
    towards the other all along: no."""
    a, b = square(0.0, 1.0), square(1.05, 2.05)
    across = line(np.c_[np.linspace(0.0, 2.05, 60), np.full(60, 0.5), np.zeros(60)])
    assert rf.over_a_rim(across, a, b)
    assert rf.over_a_rim(line(across.points[::-1]), b, a)
    assert not rf.over_a_rim(line(np.c_[np.linspace(1.0, 1.05, 10), np.full(10, 0.5), np.zeros(10)]), a, b)
    # along the side two touching loops share (distances 0 to both, up to rounding): no rim on the way
    c = square(1.0, 2.0)
    assert not rf.over_a_rim(line(np.c_[np.ones(30), np.linspace(0.2, 0.8, 30), np.zeros(30)]), a, c)
    # from the first hole's near side over the strip and across the second hole: read from its end,
    # the line comes back to the second loop only next to its start, beyond RIM_BACK of its length
    # (where two loops touch, both pass a line's ends alike): no
    assert not rf.over_a_rim(line(np.c_[np.linspace(1.0, 2.05, 40), np.full(40, 0.5), np.zeros(40)]), a, b)
    low, high = square(0.0, 1.0, 0.0), square(0.0, 1.0, 0.3)
    gap = line(np.c_[np.zeros(20), np.full(20, 0.5), np.linspace(0.0, 0.3, 20)])
    assert not rf.over_a_rim(gap, low, high)


def test_two_holes_one_face_apart_on_a_capsule_get_no_handle(monkeypatch):
    """bench/sweep.py capsule:30:1, light mode: a slab cut down the capsule and a ball cut beside it
    at the cap's pole, the two loops 0.015 apart (a strip one face wide). Unshielded, four lines from
    the small hole crossed it, passed over the strip and crossed the slab's band: a tunnel, a handle
    the capsule does not have (genus 1). Three of the four pass over a rim and join neither loop:
    the holes are capped, genus 0 (rule switched off: genus 1)."""
    model = sweep_model("capsule", 30, 1)
    res = closed_repair(model, genus=0)
    assert "pass over a rim" in res.tunnel_note
    monkeypatch.setattr(rf, "OVER_RIMS", False)
    assert topology(repair(model, RepairParams(field=FieldParams(mode="light"))).mesh.faces).genus == 1


@pytest.mark.parametrize(("near", "away", "over"), [(0.01, 3.0, False), (0.0125, 3.0, True), (0.2, 3.0, True),
                                                    (0.1, 11.0, True), (0.1, 12.0, False)])
def test_over_a_rim_reads_its_thresholds(near, away, over):
    """The line of the first test: 0.025 from the rims at the strip, 0.0122 of its length 2.05 (over
    a rim from ``near`` 0.0125 up, not at 0.01); that distance counts as the floor, 2 % of the
    length (0.041), and its distance to the first loop had risen to 0.49 at the sample nearest the
    first hole's middle (11.9 times that: over a rim for ``away`` 11, not 12)."""
    a, b = square(0.0, 1.0), square(1.05, 2.05)
    across = line(np.c_[np.linspace(0.0, 2.05, 60), np.full(60, 0.5), np.zeros(60)])
    assert rf.over_a_rim(across, a, b, near=near, away=away) is over

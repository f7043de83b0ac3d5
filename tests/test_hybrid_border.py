"""Stage I: the 16 configurations, ambiguous cells, root finding, merge."""

import numpy as np
import pytest

from algorithms.hybrid.border import CURVE, build_border, cell_segments, classify, configuration
from algorithms.hybrid.incircle import orient
from algorithms.hybrid.model import HybridModel
from algorithms.hybrid.surfaces import from_functions

CORNERS = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
MID = [(0.5, 0.0), (1.0, 0.5), (0.5, 1.0), (0.0, 0.5)]  # crossing on side k (corner k -> k+1)


def test_sixteen_configurations_classes():
    classes = [classify(c) for c in range(16)]
    assert classes.count("A") == 2 and classes.count("B") == 8
    assert classes.count("C") == 4 and classes.count("D") == 2
    assert classify(5) == classify(10) == "D" and classify(0) == classify(15) == "A"
    bits = np.array([[c >> k & 1 for k in range(4)] for c in range(16)], dtype=bool)
    assert np.array_equal(configuration(bits), np.arange(16))


@pytest.mark.parametrize("config", range(16))
@pytest.mark.parametrize("centre", [False, True])
def test_segments_join_crossed_sides_with_kept_corners_on_the_left(config, centre):
    ins = [config >> k & 1 for k in range(4)]
    segs = cell_segments(config, centre)
    crossed = {k for k in range(4) if ins[k] != ins[(k + 1) % 4]}
    assert {s for seg in segs for s in seg} == crossed
    assert len(segs) == len(crossed) // 2
    for s0, s1 in segs:
        a, b = MID[s0], MID[s1]
        if (s1 - s0) % 4 in (1, 3):  # adjacent sides cut off their shared corner
            k = s1 if s1 == (s0 + 1) % 4 else s0
            assert (orient(a, b, CORNERS[k]) > 0) == bool(ins[k])
        else:  # opposite sides: every corner on its own side
            for k in range(4):
                assert (orient(a, b, CORNERS[k]) > 0) == bool(ins[k])
    if classify(config) == "D":
        # centre inside: the kept corners are joined, so the cut-off corners are the outside ones
        cut = [s1 if s1 == (s0 + 1) % 4 else s0 for s0, s1 in segs]
        assert all(ins[k] == (0 if centre else 1) for k in cut)


def plane(domain=(-1, 1, -1, 1)):
    return from_functions(lambda u, v: u, lambda u, v: v, lambda u, v: 0 * u, domain)


def test_circle_border_on_the_curve_and_closed():
    m = HybridModel("disk-hole", plane(), lambda x, y, z: x * x + y * y - 0.36)
    b = build_border(m, cells=24)
    assert b.open_ends == 0
    curve = np.unique(b.segments[b.kinds == CURVE])
    r = np.hypot(*b.points[curve].T)
    assert np.abs(r - 0.6).max() < 1e-12  # root finding, not interpolation
    # the hole runs clockwise (kept region on the left); the outer rectangle counter-clockwise
    loops = [p for p in b.polylines if p[0] == p[-1]]
    assert len(loops) == 2
    areas = sorted(0.5 * np.sum(b.points[p[:-1], 0] * b.points[p[1:], 1] - b.points[p[1:], 0] * b.points[p[:-1], 1])
                   for p in loops)
    assert areas[0] < 0 < areas[1] and areas[1] == pytest.approx(4.0)
    # merge: every curve edge at least delta long (or a merge would have removed it)
    assert b.merged > 0


def test_ambiguous_cells_are_split():
    # a saddle x*y with a cell centred on it: corners alternate in sign (D)
    m = HybridModel("saddle", plane((-1.05, 1.0, -1.05, 1.0)), lambda x, y, z: x * y + 0.01)
    b = build_border(m, cells=2, delta=0.0)
    assert b.ambiguous_cells > 0
    assert b.open_ends == 0
    curve = np.unique(b.segments[b.kinds == CURVE])
    p = b.points[curve]
    assert np.abs(p[:, 0] * p[:, 1] + 0.01).max() < 1e-12

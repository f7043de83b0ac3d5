import numpy as np
import pytest

from algorithms.bridge_graph import (
    BoundaryEdges,
    Bridge,
    ConflictRules,
    GraphState,
    TopologyGuard,
    resample_chain,
    segment_distance,
    split_polygon,
    walk_holes,
)
from algorithms.cases import combine, disk
from algorithms.holes import SimpleHoleTest, classify_hole, polygon_self_intersects
from algorithms.topology import boundary_loops


def two_disks():
    m = combine(disk(segments=16, rings=1), disk(center=(4, 0, 0), segments=16, rings=1))
    loops = boundary_loops(m.faces)
    return m, sorted(loops, key=lambda lp: lp.min())


def test_walk_two_bridges_gives_two_disk_holes():
    m, loops = two_disks()
    b1 = Bridge(2, 25, np.array([[2.0, 0.38, 0]]), 1.0)
    b2 = Bridge(16, 27, np.array([[2.0, -0.38, 0]]), 0.9)
    holes = walk_holes(loops, [b1, b2], [np.array([34]), np.array([35])])
    assert sorted(len(h.polygon) for h in holes) == [8, 32]
    small = min(holes, key=lambda h: len(h.polygon))
    k = small.polygon.index(16)
    assert small.polygon[k:] + small.polygon[:k] == (16, 1, 2, 34, 25, 26, 27, 35)
    assert all(h.is_disk for h in holes)
    # every bridge walked once in each direction over all holes
    uses = sorted(u for h in holes for u in h.bridges)
    assert uses == [(0, -1), (0, 1), (1, -1), (1, 1)]


def test_walk_single_bridge_is_not_a_disk():
    m, loops = two_disks()
    holes = walk_holes(loops, [Bridge(2, 25, np.zeros((0, 3)), 1.0)], [np.zeros(0, dtype=int)])
    assert len(holes) == 1 and not holes[0].is_disk
    assert len(holes[0].polygon) == 16 + 16 + 2


def test_loops_without_bridges_are_their_own_holes():
    m, loops = two_disks()
    holes = walk_holes(loops, [], [])
    assert sorted(h.polygon for h in holes) == sorted(tuple(int(x) for x in lp) for lp in loops)


def test_conflicts():
    m, loops = two_disks()
    loop_of = {int(v): (k, i) for k, lp in enumerate(loops) for i, v in enumerate(lp)}
    st = GraphState(m.vertices, loop_of, [len(lp) for lp in loops],
                    ConflictRules(clearance=0.2, neighbourhood=0.5, endpoint_gap=2))
    v = m.vertices
    st.add(Bridge(2, 25, resample_chain(np.vstack([v[2], v[25]]), 0.1), 1.0))
    # a bridge between neighbours of both ends duplicates the connection
    assert "same neighbourhood" in st.conflict(Bridge(3, 24, resample_chain(np.vstack([v[3], v[24]]), 0.1), 0.9)) \
        or "endpoint" in st.conflict(Bridge(3, 24, np.zeros((0, 3)), 0.9))
    # crossing bridges conflict
    cross = Bridge(4, 23, resample_chain(np.vstack([v[16], v[27]]) * [1, -1, 1], 0.1), 0.8)
    assert st.conflict(Bridge(16, 27, resample_chain(np.vstack([v[2], v[27]]), 0.1), 0.8)) is not None
    assert cross.start == 4
    # a bridge on the other side is fine
    assert st.conflict(Bridge(16, 27, resample_chain(np.vstack([v[16], v[27]]), 0.1), 0.8)) is None


def test_resample_chain_spacing():
    pts = resample_chain(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], float), 0.25)
    assert len(pts) == 7
    np.testing.assert_allclose(np.diff(np.r_[[[0, 0, 0]], pts, [[1, 1, 0]]], axis=0).__abs__().sum(1), 0.25)


def test_split_polygon_walks_chain_both_ways():
    a, b = split_polygon((0, 1, 2, 3), 0, 2, np.array([9]))
    assert a == (0, 1, 2, 9) and b == (2, 3, 0, 9)
    with pytest.raises(ValueError):
        split_polygon((0, 1, 2), 1, 1, np.array([]))


def circle(n, z=lambda t: 0 * t):
    t = 2 * np.pi * np.arange(n) / n
    return np.stack([np.cos(t), -np.sin(t), z(t)], axis=1)  # clockwise seen from +z


def test_simple_hole_test():
    up = np.tile([0, 0, 1.0], (32, 1))
    assert classify_hole(circle(32), up, SimpleHoleTest()).simple
    saddle = classify_hole(circle(32, lambda t: 0.8 * np.cos(2 * t)), up, SimpleHoleTest())
    assert not saddle.simple and "not flat" in saddle.reasons[0]
    big = classify_hole(circle(300), np.tile([0, 0, 1.0], (300, 1)), SimpleHoleTest())
    assert not big.simple and "300 boundary vertices" in big.reasons[0]
    assert classify_hole(circle(32), up, SimpleHoleTest.for_method("fan")).simple


def test_self_intersection():
    eight = np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float)
    assert polygon_self_intersects(eight)
    assert not polygon_self_intersects(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float))


def _walk_partition(loops, bridges):
    """Brute force: the loop vertices of each walk of walk_holes, bridge ends left out (a bridge end
    lies on two walks: the one arriving along its loop and the one leaving by its dart)."""
    chains = [np.zeros(0, dtype=int) for _ in bridges]
    ends = {v for b in bridges for v in (b.start, b.end)}
    return [frozenset(h.polygon) - ends for h in walk_holes(loops, bridges, chains)]


def test_topology_guard_incremental_walks_match_a_full_walk():
    # three disks (three islands, one loop each) and random non-touching bridges between their loops
    m = combine(disk(segments=12, rings=1), disk(center=(4, 0, 0), segments=12, rings=1),
                disk(center=(0, 4, 0), segments=12, rings=1))
    loops = sorted(boundary_loops(m.faces), key=lambda lp: lp.min())
    rng = np.random.default_rng(4)
    for _ in range(20):
        guard = TopologyGuard(loops, [0, 1, 2])
        free = {int(v) for lp in loops for v in lp}
        bridges = []
        effects = []
        for _ in range(5):
            a, b = rng.choice(sorted(free), 2, replace=False)
            a, b = int(a), int(b)
            effects.append(guard.effect(a, b))
            br = Bridge(a, b, np.zeros((0, 3)), 1.0)
            bridges.append(br)
            guard.add(br)
            free -= {a, b}
            # every walk of the full walk: its dart vertices carry one label, distinct walks differ
            labels = [{guard.walk_of[v] for v in g} for g in _walk_partition(loops, bridges)]
            labels = [lab for lab in labels if lab]
            assert all(len(lab) == 1 for lab in labels)
            assert len({next(iter(lab)) for lab in labels}) == len(labels)
        # the effect of each bridge matches what it did to the count of walks and components
        n_walks = len(loops)
        comps = 3
        for i, e in enumerate(effects):
            holes = walk_holes(loops, bridges[:i + 1], [np.zeros(0, dtype=int)] * (i + 1))
            if e == "connect":
                comps -= 1
                assert len(holes) == n_walks - 1
            elif e == "split":
                assert len(holes) == n_walks + 1
            else:
                assert e == "handle" and len(holes) == n_walks - 1
            n_walks = len(holes)
        assert comps == len(guard.components())


def test_a_bridge_along_the_boundary_conflicts():
    # three unit triangles in a row along the x axis, each touching the next at a corner (copies:
    # vertices 2/3 and 5/6 sit at the same points), as a cut wall leaves them; the middle one is
    # half as tall
    V = np.array([[0, 0, 0], [0.5, 1, 0], [1, 0, 0], [1, 0, 0], [1.5, 0.5, 0], [2, 0, 0], [2, 0, 0],
                  [2.5, 1, 0], [3, 0, 0], [1.5, -1, 0]], dtype=float)
    loops = [np.array([0, 2, 1]), np.array([3, 5, 4]), np.array([6, 8, 7])]
    edges = BoundaryEdges(V, loops)
    none = np.zeros((0, 3))
    # from the first triangle's corner 2 to the copy 6: along the middle triangle's edge 3-5
    assert edges.runs_along(Bridge(2, 6, none, 1.0), V, 0.1)
    # from 0 to 8 along the bottom: through the corners of the other triangles
    assert edges.runs_along(Bridge(0, 8, none, 1.0), V, 0.1)
    # between the tops of the first and last triangles: 0.5 clear of the middle one's apex 4
    # (a quarter of its length of 2.0: above the fraction 0.1, below 0.3)
    top = Bridge(1, 7, none, 1.0)
    assert not edges.runs_along(top, V, 0.1) and edges.runs_along(top, V, 0.3)
    # edges at the bridge's own ends do not count: 1 -> 4 leaves along nothing but its own loops
    assert not edges.runs_along(Bridge(1, 4, none, 1.0), V, 0.1)
    # a curved bridge: its middle half is tested by arc length, here a detour 1 above the row
    arc = Bridge(0, 8, np.array([[0, 2, 0], [3, 2, 0]], dtype=float), 1.0)
    assert not edges.runs_along(arc, V, 0.1)
    # in the graph: a conflict with its reason
    loop_of = {int(v): (k, i) for k, lp in enumerate(loops) for i, v in enumerate(lp)}
    state = GraphState(V, loop_of, [3, 3, 3], ConflictRules(0.1, 0.5), boundary=edges)
    assert "runs along the boundary" in state.conflict(Bridge(2, 6, none, 1.0))
    assert state.conflict(top) is None


def test_segment_distance_against_brute_force():
    rng = np.random.default_rng(3)
    p0, p1, q0, q1 = (rng.normal(size=(120, 3)) for _ in range(4))
    d = segment_distance(p0, p1, q0, q1)
    g = np.linspace(0.0, 1.0, 501)
    brute = np.array([np.linalg.norm(p0[k] + g[:, None, None] * (p1[k] - p0[k])
                                     - q0[k] - g[None, :, None] * (q1[k] - q0[k]), axis=2).min() for k in range(120)])
    # a feasible pair of points: never below the true distance; the grid is 1/500 fine
    assert (d <= brute + 1e-12).all() and np.abs(d - brute).max() < 5e-3
    # parallel, crossing, a point against a segment
    o = np.zeros(3)
    assert segment_distance(o, np.array([1.0, 0, 0]), np.array([0.5, 1, 0]),
                            np.array([2.0, 1, 0])) == pytest.approx(1.0)
    assert segment_distance(np.array([-1.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0, -1.0, 0]),
                            np.array([0, 1.0, 0])) == pytest.approx(0.0)
    assert segment_distance(o, o, np.array([0.5, 1, 0]), np.array([2.0, 1, 0])) == pytest.approx(np.hypot(0.5, 1))


def test_a_bridge_that_crosses_a_boundary_edge_runs_along_it():
    # a chord that crosses a boundary edge at a point no sample would land on exactly
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5131, -0.3, 0], [0.5131, 0.3, 0], [0.6, 0.3, 0]], dtype=float)
    edges = BoundaryEdges(V, [np.array([2, 3, 4])])
    assert edges.runs_along(Bridge(0, 1, np.zeros((0, 3)), 1.0), V, 0.001)
    V2 = V.copy()
    V2[2:, 2] = 0.01  # lifted 0.01 off the chord: 1 % of its length
    lifted = BoundaryEdges(V2, [np.array([2, 3, 4])])
    assert not lifted.runs_along(Bridge(0, 1, np.zeros((0, 3)), 1.0), V2, 0.005)
    assert lifted.runs_along(Bridge(0, 1, np.zeros((0, 3)), 1.0), V2, 0.02)


def test_a_bare_bridge_along_an_edge_inside_a_fragment_is_an_edge_of_the_surface():
    """A set-aside fragment is put back into the hole it hangs at: a bare bridge along an edge
    between two of its faces would give that edge four faces (loose triangles of a sphere touching
    at corners). Its border edges stay open (a bridge there and the fragment's face: the walk
    decides)."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0], [3, 0, 0], [3, 1, 0]], dtype=float)
    be = BoundaryEdges(v, [np.array([0, 1, 2])], np.array([[0, 1, 2]]),
                       fragments=[np.array([[3, 5, 4], [5, 6, 4]])])
    assert be.is_edge(Bridge(4, 5, np.zeros((0, 3)), 1.0))  # inside the fragment
    assert be.is_edge(Bridge(1, 0, np.zeros((0, 3)), 1.0))  # an edge of the surface
    assert not be.is_edge(Bridge(3, 4, np.zeros((0, 3)), 1.0))  # the fragment's border
    assert not be.is_edge(Bridge(1, 3, np.zeros((0, 3)), 1.0))
    assert not be.is_edge(Bridge(4, 5, np.array([[2.5, 0.5, 0.0]]), 1.0))  # a chain is no edge

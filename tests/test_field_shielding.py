"""Shielding (15): the BVH segment test against brute force; a wall blocks, removing it unblocks."""

import numpy as np
import pytest

from algorithms.boundary import loop_frames
from algorithms.cases import combine, disk, icosphere
from algorithms.field.indicator import IndicatorField, sources_from_frames
from algorithms.field.shielding import blocked, build_bvh, mesh_bvh
from algorithms.mesh import Mesh
from algorithms.params import FieldParams


def brute_blocked(v, f, x, o):
    """Plain Moller-Trumbore over every triangle (non-coplanar segments only)."""
    out = np.zeros(len(x), dtype=bool)
    for i in range(len(x)):
        d = o[i] - x[i]
        for tri in v[f]:
            e1, e2 = tri[1] - tri[0], tri[2] - tri[0]
            pv = np.cross(d, e2)
            det = e1 @ pv
            if abs(det) < 1e-14:
                continue
            tv = x[i] - tri[0]
            u = (tv @ pv) / det
            qv = np.cross(tv, e1)
            w = (d @ qv) / det
            t = (e2 @ qv) / det
            if u >= 0 and w >= 0 and u + w <= 1 and 1e-6 < t < 1 - 1e-6:
                out[i] = True
                break
    return out


def test_bvh_agrees_with_brute_force():
    m = icosphere(2)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(300, 3)) * 1.5
    o = rng.normal(size=(300, 3)) * 1.5
    got = blocked(mesh_bvh(m), x, o)
    ref = brute_blocked(m.vertices, m.faces, x, o)
    assert got.mean() > 0.2 and (~got).mean() > 0.2
    np.testing.assert_array_equal(got, ref)


def test_bvh_boxes_contain_their_triangles():
    m = icosphere(3)
    b = mesh_bvh(m)
    leaf = b.node_left < 0
    for k in np.flatnonzero(leaf):
        t = b.tri[b.node_start[k]:b.node_start[k] + b.node_count[k]].reshape(-1, 3)
        assert np.all(t >= b.node_min[k] - 1e-12) and np.all(t <= b.node_max[k] + 1e-12)
    inner = np.flatnonzero(~leaf)
    for k in inner:
        for c in (b.node_left[k], b.node_right[k]):
            assert np.all(b.node_min[c] >= b.node_min[k] - 1e-12) and np.all(b.node_max[c] <= b.node_max[k] + 1e-12)
    assert b.node_count[leaf].sum() == m.n_faces


def wall(x=1.3, h=1.0):
    """A vertical square wall in the plane x = const, from y, z = -h to h (two triangles)."""
    v = np.array([[x, -h, -h], [x, h, -h], [x, h, h], [x, -h, h]], dtype=float)
    return Mesh(v, np.array([[0, 1, 2], [0, 2, 3]]))


def test_wall_blocks_and_removing_it_unblocks():
    disks = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    with_wall = combine(disks, wall())
    a, b = np.array([[1.0, 0, 0]]), np.array([[1.6, 0, 0]])
    assert blocked(mesh_bvh(with_wall), a, b)[0]
    assert not blocked(mesh_bvh(disks), a, b)[0]
    # the field: with the wall every source of disk B is shielded, so Omega at A's facing point is 0
    fr = [f for f in loop_frames(disks) if f.island == 1]
    src = sources_from_frames(fr)
    p = FieldParams(mode="full", lc=0.6)
    x = np.array([[1.0, 0, 0]])
    h_wall = IndicatorField(src, p, 0.6, bvh=mesh_bvh(with_wall)).evaluate(x).H[0]
    h_free = IndicatorField(src, p, 0.6, bvh=mesh_bvh(disks)).evaluate(x).H[0]
    assert np.abs(h_wall).max() == 0.0 and np.abs(h_free).max() > 0.1


def test_coplanar_segment_across_an_island_is_blocked():
    disks = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    bvh = mesh_bvh(disks)
    # from disk A's boundary to disk B's far side: runs inside disk B's plane across its interior
    assert blocked(bvh, [[1.0, 0, 0]], [[3.6, 0, 0]])[0]
    # to B's near side: touches B only at the end point (its triangles there are incident to O,
    # and the open segment ends there): not blocked
    ov = np.array([257 + 193 + 32])
    assert not blocked(bvh, [[1.0, 0, 0]], [[1.6, 0, 0]], o_vertex=ov)[0]


def test_triangles_incident_to_the_end_points_are_ignored():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    bvh = build_bvh(v, np.array([[0, 1, 2]]))
    x, o = np.array([[0.2, 0.2, -1.0]]), np.array([[0.2, 0.2, 1.0]])
    assert blocked(bvh, x, o)[0]
    assert not blocked(bvh, x, o, o_vertex=np.array([1]))[0]
    assert not blocked(bvh, x, o, x_vertex=np.array([2]))[0]


@pytest.mark.parametrize("n", [0, 1, 5])
def test_tiny_meshes(n):
    rng = np.random.default_rng(n)
    v = rng.normal(size=(3 * n, 3)) if n else np.zeros((0, 3))
    f = np.arange(3 * n).reshape(-1, 3)
    bvh = build_bvh(v, f)
    x, o = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    np.testing.assert_array_equal(blocked(bvh, x, o), brute_blocked(v, f, x, o) if n else np.zeros(50, bool))


def test_visibility_coherence_agrees_with_exact_shielding():
    """Coherence along sources (shield_stride, coherence_deg) and across points (point_stride)
    interpolates verdicts between exact anchors; stride 1 and point_stride 1 decide every pair."""
    from algorithms.bridges import attraction_index, field_context
    from algorithms.demos import demo
    from algorithms.io import load_model

    m = load_model(demo("two-caps", "repair").path)
    om = {}
    for key, kw in (("exact", dict(shield_stride=1, point_stride=1)), ("default", {}),
                    ("sources only", dict(point_stride=1))):
        ctx = field_context(m, FieldParams(mode="full", **kw))
        om[key] = np.concatenate(attraction_index(ctx)[0])
    assert om["exact"].max() > 0
    for key in ("default", "sources only"):
        np.testing.assert_allclose(om[key], om["exact"], rtol=0, atol=0.005 * om["exact"].max())


def test_coherence_keeps_a_partial_wall():
    """A wall that hides part of disk B from part of disk A's boundary: with coherence along
    sources and across points the field of every point of A's loop stays close to the exact one
    (every pair tested), and the wall still changes it."""
    disks = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    fr_a = [f for f in loop_frames(disks) if f.island == 0][0]
    src = sources_from_frames([f for f in loop_frames(disks) if f.island == 1])
    n = len(fr_a.vertices)
    loop, pos = np.zeros(n, dtype=np.int64), np.arange(n)
    H = {}
    for name, mesh in (("wall", combine(disks, wall(h=0.35))), ("none", disks)):
        for key, kw in (("exact", dict(shield_stride=1, point_stride=1)), ("coherent", dict(point_stride=4))):
            p = FieldParams(mode="full", lc=0.6, **kw)
            f = IndicatorField(src, p, 0.6, bvh=mesh_bvh(mesh))
            H[name, key] = f.evaluate(fr_a.points, x_vertex=fr_a.vertices, x_loop=loop, x_pos=pos).H
    scale = np.abs(H["none", "exact"]).max()
    changed = np.abs(H["wall", "exact"] - H["none", "exact"]).max(axis=(1, 2)) > 0.05 * scale
    assert 0 < changed.sum() < n  # the wall hides B from some of A's points, not from all
    np.testing.assert_allclose(H["wall", "coherent"], H["wall", "exact"], atol=0.02 * scale)
    np.testing.assert_allclose(H["none", "coherent"], H["none", "exact"], atol=1e-4 * scale)


def test_key_points_split_runs_of_consecutive_points():
    from algorithms.field.indicator import key_points

    loop = np.array([0, 0, 0, 0, 0, 0, 1, 1, 1, -1, -1])
    pos = np.array([0, 1, 2, 3, 4, 5, 7, 8, 10, 0, 1])
    krow, n0, n1, p0, p1, wgt, keys, rest = key_points(loop, pos, 4)
    # runs: [0..5], [6, 7], [8], [9], [10]; keys: 0, 4, 5 | 6, 7 | 8 | 9 | 10
    np.testing.assert_array_equal(keys, [0, 4, 5, 6, 7, 8, 9, 10])
    np.testing.assert_array_equal(rest, [1, 2, 3])
    np.testing.assert_array_equal(p0[rest], [0, 0, 0])
    np.testing.assert_array_equal(p1[rest], [4, 4, 4])
    np.testing.assert_allclose(wgt[rest], [0.25, 0.5, 0.75])
    np.testing.assert_array_equal(krow[keys], np.arange(8))
    assert np.all(n0[keys] == -1) and np.all(krow[rest] == -1)
    k1 = key_points(loop, pos, 1)
    np.testing.assert_array_equal(k1[6], np.arange(11))


def test_shield_stride_is_validated():
    with pytest.raises(ValueError, match="parameter shield_stride="):
        FieldParams(shield_stride=0)
    with pytest.raises(ValueError, match="parameter point_stride="):
        FieldParams(point_stride=0)
    with pytest.raises(ValueError, match="parameter coherence_deg="):
        FieldParams(coherence_deg=90)


def test_occluder_hint_changes_no_answer():
    """(15) with the last occluder tried first: the same answers as without a hint, whatever the hint."""
    from algorithms.field.shielding import segment_blocked_hint

    m = icosphere(2)
    b = mesh_bvh(m)
    rng = np.random.default_rng(3)
    x = rng.normal(size=(200, 3)) * 1.5
    o = rng.normal(size=(200, 3)) * 1.5
    ref = brute_blocked(m.vertices, m.faces, x, o)
    stack, work = np.empty(64, dtype=np.int64), np.empty((2, 3))
    hint = -1
    for i in range(len(x)):
        for h in (hint, int(rng.integers(b.n_triangles)), -1):
            hit, occ = segment_blocked_hint(x[i], o[i], -1, -1, *b.arrays(), b.scale, h, stack, work)
            assert hit == ref[i] and (occ >= 0) == hit
        hint = occ if hit else hint


def test_coherence_across_points_skips_a_point_off_its_key_points_chord():
    """Points labelled consecutive along a loop, but the middle one far from its two key points
    (a hairpin) and hidden behind a wall from which they are not: it is decided by itself."""
    disks = combine(disk((0, 0, 0)), disk((2.6, 0, 0)))
    src = sources_from_frames([f for f in loop_frames(disks) if f.island == 1])
    v = np.array([[1.2, -3, 0.5], [1.2, 3, 0.5], [1.2, 3, 2.5], [1.2, -3, 2.5]], dtype=float)
    high_wall = Mesh(v, np.array([[0, 1, 2], [0, 2, 3]]))  # hides B from z ~ 1.5, not from z = 0
    x = np.array([[1.0, 0.005, 0.0], [1.0, 0.0, 1.5], [1.0, -0.005, 0.0]])
    loop, pos = np.zeros(3, dtype=np.int64), np.arange(3)
    H = {}
    for key, kw in (("exact", dict(shield_stride=1, point_stride=1)), ("coherent", dict(point_stride=2))):
        f = IndicatorField(src, FieldParams(mode="full", lc=0.6, **kw), 0.6, bvh=mesh_bvh(combine(disks, high_wall)))
        H[key] = f.evaluate(x, x_loop=loop, x_pos=pos).H
    assert np.abs(H["exact"][0]).max() > 0.1 and np.abs(H["exact"][1]).max() == 0.0
    np.testing.assert_allclose(H["coherent"], H["exact"], rtol=1e-9, atol=1e-12)


def test_mesh_bvh_is_built_once_per_mesh():
    from algorithms.cases import icosphere

    m = icosphere(2)
    b = mesh_bvh(m)
    assert mesh_bvh(m) is b  # the same (immutable) mesh: the same BVH
    m2 = icosphere(2)
    b2 = mesh_bvh(m2)
    assert b2 is not b and b2.n_triangles == b.n_triangles == len(m.faces)

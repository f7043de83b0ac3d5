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
    """shield_stride > 1 interpolates visibility between far anchors; near sources stay exact."""
    from algorithms.bridges import attraction_index, field_context
    from algorithms.demos import demo
    from algorithms.io import load_model

    m = load_model(demo("two-caps", "repair").path)
    om = {}
    for stride in (1, 8):
        ctx = field_context(m, FieldParams(mode="full", shield_stride=stride))
        om[stride] = np.concatenate(attraction_index(ctx)[0])
    assert om[1].max() > 0
    np.testing.assert_allclose(om[8], om[1], rtol=0.02, atol=0.02 * om[1].max())


def test_shield_stride_is_validated():
    with pytest.raises(ValueError, match="parameter shield_stride="):
        FieldParams(shield_stride=0)


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

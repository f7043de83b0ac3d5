"""Straight bridges between components that no force line joined (repair._join_components) never
end where a kept bridge ends: three such bridges met at one vertex of featuretype cut by balls and
a slab, and the hole walk failed ("two bridges meet at vertex ...")."""

from __future__ import annotations

import numpy as np

from algorithms.boundary import loop_frames
from algorithms.cases import combine, disk
from algorithms.repair import _join_components


def test_join_components_avoids_taken_ends():
    mesh = combine(disk((0.0, 0.0, 0.0), 1.0, segments=32), disk((2.5, 0.0, 0.0), 1.0, segments=32))
    frames = loop_frames(mesh)
    comps = [[frames[0].island], [frames[1].island]]
    a, b, q = _join_components(mesh.vertices, frames, comps, lc=1.0, ki=1.0)
    # the nearest points of the two unit disks: x = 1 and x = 1.5
    assert np.allclose(mesh.vertices[[a, b], 0], [1.0, 1.5]) and q > 0
    a2, b2, _ = _join_components(mesh.vertices, frames, comps, lc=1.0, ki=1.0, taken={a, b})
    assert a2 != a and b2 != b
    assert np.linalg.norm(mesh.vertices[a2] - mesh.vertices[b2]) < 0.6  # still a short bridge
    every = {int(v) for f in frames for v in f.vertices}
    assert _join_components(mesh.vertices, frames, comps, lc=1.0, ki=1.0, taken=every) is None


def test_join_components_avoids_bridges_along_the_boundary():
    # two unit disks with a third, small disk between them whose rim touches the line of centres:
    # the best straight bridge (x = 1 to x = 1.5) runs across the small disk's rim and is refused
    from algorithms.bridge_graph import BoundaryEdges

    small = disk((1.25, 0.1, 0.0), 0.1, segments=16)
    mesh = combine(combine(disk((0.0, 0.0, 0.0), 1.0, segments=32), disk((2.5, 0.0, 0.0), 1.0, segments=32)),
                   small)
    frames = loop_frames(mesh)
    big = [f for f in frames if len(f.vertices) == 32]
    comps = [[big[0].island], [big[1].island]]
    a, b, _ = _join_components(mesh.vertices, big, comps, lc=1.0, ki=1.0)
    assert np.allclose(mesh.vertices[[a, b], 0], [1.0, 1.5])
    edges = BoundaryEdges(mesh.vertices, [f.vertices for f in frames])
    a2, b2, q2 = _join_components(mesh.vertices, big, comps, lc=1.0, ki=1.0, boundary=edges, along=0.02)
    assert {a2, b2} != {a, b} and q2 > 0
    mid = (mesh.vertices[a2] + mesh.vertices[b2]) / 2
    assert np.linalg.norm(mid[:2] - [1.25, 0.1]) > 0.1 + 1e-9  # clear of the small disk's rim


def test_join_components_leaves_islands_out_of_reach_apart():
    """Two unit disks (width 2 by their mean radius) a width short of ISLAND_REACH widths apart are
    joined; a width beyond it, they are separate objects, not joined."""
    from algorithms.repair import ISLAND_REACH

    reach = 2.0 * ISLAND_REACH
    for gap, joined in ((reach - 1.0, True), (reach + 1.0, False)):
        mesh = combine(disk((0.0, 0.0, 0.0), 1.0, segments=32), disk((2.0 + gap, 0.0, 0.0), 1.0, segments=32))
        frames = loop_frames(mesh)
        comps = [[frames[0].island], [frames[1].island]]
        assert (_join_components(mesh.vertices, frames, comps, lc=1.0, ki=1.0) is not None) == joined


def test_two_objects_scanned_together_come_back_as_two_closed_surfaces():
    """Two spheres with a hole each, 4 diameters apart: before ISLAND_REACH the force lines between
    them (their quality does not depend on the distance) joined them by a tube 8 long. Near each
    other, holes facing, they are still joined into one surface."""
    import trimesh

    from algorithms.metrics import topology
    from algorithms.normalize import normalize
    from algorithms.repair import repair

    s = trimesh.creation.icosphere(3)
    v, f = s.vertices, s.faces
    cap = np.linalg.norm(v[f].mean(axis=1) - [1.0, 0.0, 0.0], axis=1) < 0.4  # a hole at x = +1
    one = f[~cap]
    mirrored = v * [-1.0, 1.0, 1.0]  # the second sphere's hole at x = -1, facing the first
    for shift, pieces in ((10.0, 2), (2.3, 1)):
        model = normalize(np.vstack([v, mirrored + [shift, 0.0, 0.0]]), np.vstack([one, one[:, ::-1] + len(v)]))
        res = repair(model)
        t = topology(res.mesh.faces)
        assert t.watertight and t.components == pieces and t.genus == 0, (shift, t)
        if pieces == 2:
            assert "separate objects" in res.tunnel_note  # the report's notes ("tunnels")


def test_force_lines_between_far_islands_are_refused():
    """Two spheres 10 apart, both holes facing up and away from +x (around icosphere vertex 0): lines
    from one hole arrive at the other (quality 0.67: it does not fall with the distance); each is
    refused as joining separate objects, and both come back closed, apart."""
    import trimesh

    from algorithms.metrics import topology
    from algorithms.normalize import normalize
    from algorithms.repair import repair

    s = trimesh.creation.icosphere(3)
    v, f = s.vertices, s.faces
    one = f[np.linalg.norm(v[f].mean(axis=1) - v[0], axis=1) >= 0.4]
    res = repair(normalize(np.vstack([v, v + [10.0, 0.0, 0.0]]), np.vstack([one, one + len(v)])))
    assert any("separate objects" in why for _, why in res.rejected)
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 2 and t.genus == 0

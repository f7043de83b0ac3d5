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

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

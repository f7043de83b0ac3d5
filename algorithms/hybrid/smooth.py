"""A finishing pass after Stage III (choice, not in the paper): smart Laplacian smoothing.

Each interior vertex is moved, in (u, v), to the mean of its neighbours' parameters (then onto
the surface through R); the move is kept only if every triangle around it stays counter-clockwise
in (u, v) and the smallest 3D angle around the vertex does not decrease. So the minimum angle
bound of the refinement is kept and the median improves. Border vertices never move.
Sequential (each accepted move changes its neighbours' fans); the surface is evaluated once per pass.
"""

from __future__ import annotations

import numpy as np

from .cdt import Triangulation
from .incircle import min_angle_3d, orient


def smooth(tri: Triangulation, *, passes: int = 2) -> int:
    """Returns the number of accepted moves."""
    border = set(tri.border_vertices().tolist())
    verts = sorted({v for t, al in zip(tri.tv, tri.alive) if al for v in t} - border)
    accepted = 0
    for _ in range(passes):
        fans = {v: tri.fan(v) for v in verts}
        targets = []
        for v in verts:
            nb = {w for t in fans[v] for w in tri.tv[t] if w != v}
            targets.append((sum(tri.uv[w][0] for w in nb) / len(nb), sum(tri.uv[w][1] for w in nb) / len(nb)))
        T = np.array(targets).reshape(-1, 2)
        Q = tri.surface(T[:, 0], T[:, 1]).tolist()
        for v, tgt, q in zip(verts, targets, Q):
            fan = fans[v]
            before = min(min_angle_3d(*(tri.p3[w] for w in tri.tv[t]))[0] for t in fan)
            old_uv, old_p = tri.uv[v], tri.p3[v]
            ok = True
            for t in fan:
                tv = tri.tv[t]
                i = tv.index(v)
                if orient(tgt, tri.uv[tv[(i + 1) % 3]], tri.uv[tv[(i + 2) % 3]]) <= 0:
                    ok = False
                    break
            if not ok:
                continue
            tri.uv[v], tri.p3[v] = tgt, (q[0], q[1], q[2])
            after = min(min_angle_3d(*(tri.p3[w] for w in tri.tv[t]))[0] for t in fan)
            if after < before:
                tri.uv[v], tri.p3[v] = old_uv, old_p
            else:
                accepted += 1
    return accepted

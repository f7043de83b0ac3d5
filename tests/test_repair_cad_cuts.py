"""Cuts of the CAD part (featuretype) that no bench case has. A slab across the part leaves a
two-face island whose two bridges end at neighbouring vertices of its loop; a force line then
split the hole by a bare chord between them, which already was the island's border edge: the
output had an edge with four faces. A bare chord that is an edge gets a vertex midway. The slab
also cuts through a through-hole whose rim is one loop and whose lower part joined the slab's loop,
which island bridges reach: the tunnel rule must consider that loop too (spec §6 step 2: all
non-trivial boundaries), or the part comes back with genus 7 instead of 9."""

from __future__ import annotations

import numpy as np
from conftest import data_file
from test_repair import assert_input_kept

from algorithms.cases import cut, face_centroids
from algorithms.io import load_raw
from algorithms.mesh import Mesh
from algorithms.metrics import topology
from algorithms.normalize import normalize
from algorithms.params import FieldParams
from algorithms.repair import RepairParams, repair
from algorithms.topology import edge_table


def test_slab_across_the_part_gives_a_manifold_surface():
    part = Mesh(*load_raw(data_file("featuretype.stl")))
    n = np.array([-0.3338057414969535, 0.38549451719908506, 0.8602137549197368])
    case = cut(part, np.abs(face_centroids(part) @ n - 1.4508043208078552) < 0.2771542226709827 / 2,
               name="featuretype slab", description="")
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    assert edge_table(res.mesh.faces).counts.max() == 2
    t = topology(res.mesh.faces)
    assert t.watertight and t.oriented and t.components == 1 and t.genus == 9
    assert_input_kept(model, res.mesh)

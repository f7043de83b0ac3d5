"""Island bridges must not make a handle the surface does not have. A slab and three balls cut the
closed bunny into three islands, one of them a small piece (the base of an ear) inside the band
between the other two. The force lines from the small piece to one neighbour arrive in crossed order;
a bridge across the others made the repaired bunny a torus (genus 1). A handle between two loops
is a second band (a torus cut in pieces: tests/test_repair.py), never a line across the bridges of
the same two loops."""

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


def test_small_island_in_a_band_gives_no_handle():
    bunny = Mesh(*load_raw(data_file("bunny_closed.ply")))
    c = face_centroids(bunny)
    remove = np.zeros(bunny.n_faces, dtype=bool)
    for v, r in ((8750, 0.10617700084720895), (10710, 0.04107739867711735), (9156, 0.12875076387533388)):
        remove |= np.linalg.norm(c - bunny.vertices[v], axis=1) < r
    n = np.array([0.986650628621891, 0.11380560045944446, -0.11648528810151286])
    remove |= np.abs(c @ n - 0.14964918138164274) < 0.02186594822575804 / 2
    case = cut(bunny, remove, name="bunny slab and balls", description="")
    model = normalize(case.incomplete.vertices, case.incomplete.faces)
    res = repair(model, RepairParams(field=FieldParams(mode="light")))
    assert res.class_found == "ICM3"
    t = topology(res.mesh.faces)
    assert t.watertight and t.components == 1 and t.genus == 0
    assert any("crossed order" in why for _, why in res.rejected)
    assert_input_kept(model, res.mesh)

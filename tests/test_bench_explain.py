"""bench.explain, the sweep's debugging aid: its tables agree with the cut and with the repair."""

import numpy as np
import pytest

from algorithms.boundary import summarize
from algorithms.normalize import normalize
from algorithms.topology import boundary_loops, euler_characteristic, islands
from bench.explain import explain, text
from bench.sweep import cut_named


def test_explain_a_torus_cut_into_islands_reads_its_islands_loops_and_bridges():
    """thin-torus:2:1 (a sweep cut into three islands, light mode): the tables count what the
    normalised cut has and what the repair did. The islands' Euler characteristics add up to the
    surface's once the vertices where islands touch are counted once, every loop is one island's
    and the loops are the surface's boundary loops, every island bridge joins loops of two islands
    between which a line arrived, and the per-loop worst distances split the score's sample points
    (their largest is the score's Hausdorff distance)."""
    name = "thin-torus:2:1"
    r = explain(name, samples=4000)
    case = cut_named(name)
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    f = model.mesh.faces
    n, lab = islands(f)
    assert len(r["islands"]) == n == 2  # the third island, a single face, is set aside
    assert r["set_aside"] == len(case.faces) - len(f) == 1
    # islands are edge-connected: those touching at a vertex share it, so their Euler
    # characteristics add up to more than the surface's
    shared = sum(len(np.unique(f[lab == i])) for i in range(n)) - len(np.unique(f))
    assert sum(i["euler"] for i in r["islands"]) - shared == euler_characteristic(f)
    assert all(i["genus"] >= 0 and float(i["genus"]).is_integer() for i in r["islands"])
    assert sum(i["faces"] for i in r["islands"]) == len(f)
    assert sum(i["loops"] for i in r["islands"]) == len(r["loops"]) == len(boundary_loops(f))
    assert sum(lp["vertices"] for lp in r["loops"]) == sum(len(lp) for lp in boundary_loops(f))
    assert {lp["island"] for lp in r["loops"]} <= {i["island"] for i in r["islands"]}
    # island bridges join loops of two islands; the report counts each kept bridge once
    island_of = {lp["loop"]: lp["island"] for lp in r["loops"]}
    joins = [(a, b) for (kind, a, b), n in r["bridges"].items() if kind == "island" for _ in range(n)]
    assert joins and all(island_of[a] != island_of[b] for a, b in joins)
    # every island line the report counts between two loops of different islands was traced
    assert all((a, b) in r["lines"] or (b, a) in r["lines"] for a, b in joins)
    worst = np.array(r["worst"]["ours"])
    assert worst.shape == (len(r["loops"]), 2) and np.isfinite(worst).all() and (worst >= 0).all()
    # the per-loop maxima split the points the score measures: the largest is its Hausdorff distance
    assert worst.max() < 100.0
    assert worst.max() == pytest.approx(100 * r["score"]["hausdorff"], rel=1e-9)
    assert r["score"]["topology_right"] and r["score"]["genus"] == 1
    out = text(r)
    assert out.startswith(f"{name} (light): truth genus 1")
    assert "topology right" in out and "bridges kept" in out


def test_the_rim_table_measures_a_tube_cut_square_and_a_round_hole():
    """rim_table on a thin torus cut by a ball across its tube (two rims facing each other, the
    tube's wall square on each cut: the square test passes) and on a sphere with two holes (flat
    holes: no pair is steep, and without a line between them none is listed)."""
    from algorithms import cases as gen
    from bench.cases import ball
    from bench.explain import rim_table

    t = gen.torus(1.0, 0.15, 96, 16)
    cut = gen.cut(t, ball(t, np.array([1.15, 0.0, 0.0]), 0.35), name="tube", description="", free_points=0, seed=1)
    frames = list(summarize(normalize(cut.incomplete.vertices, cut.incomplete.faces)).loops)
    (row,) = rim_table(frames, {})
    assert row["pair"] == (0, 1) and row["same_island"] and row["square"] and row["slanted"]
    assert max(row["rim"]) < 0.3 and min(row["facing"]) > 0.6 and min(row["across"]) > 0.8
    assert not row["between"] and row["distance"] == pytest.approx(
        np.linalg.norm(frames[0].points.mean(axis=0) - frames[1].points.mean(axis=0)), rel=0.05)
    s = gen.icosphere(4)
    holes = ball(s, np.array([0.0, 0.0, 1.0]), 0.3) | ball(s, np.array([0.0, 0.0, -1.0]), 0.3)
    cut = gen.cut(s, holes, name="s", description="", free_points=0, seed=1)
    frames = list(summarize(normalize(cut.incomplete.vertices, cut.incomplete.faces)).loops)
    assert len(frames) == 2 and rim_table(frames, {}) == []
    (row,) = rim_table(frames, {(0, 1): [0.5]})  # a line between them: listed, no test passes
    assert min(row["rim"]) > 0.9 and not row["square"] and not row["slanted"]

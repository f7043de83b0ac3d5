"""Random-cut sweep: the repair on many cuts it was not tuned on, beside MeshLib's bridge fill.

    python -m bench.sweep [--seeds 1-10] [--per-seed 2] [--models a,b] [--modes light,full]
                          [--styles balls,cross,speckle,patches] [--peers meshlib] [--only MODEL[+STYLE]:SEED:IT]
                          [--save DIR] [--out F.jsonl] [--write]

The bench cases (bench/cases.py) are fixed; this makes new ones "the same way" (balls of faces
and slabs removed from a closed model, free points sampled on what was removed) from a seed, so a
change can be checked against cases nobody looked at while making it. Each cut is a row per
method: topology right (watertight, one component, the model's genus), the share of input faces
kept, Hausdorff distance to the model (fraction of its diagonal), the unforced min patch angle and
the wall time (scored as bench/repair.py scores). A cut is named MODEL:SEED:IT; ``--only`` re-runs
one, ``--save`` writes it (vertices, faces, free points, truth) as an .npz for debugging. Other cut
styles (``--styles``, :func:`make_cut`): crossing slabs, faces removed at random and geodesic patches, the kinds of
cut the rules were not made on (MODEL+cross:SEED:IT, MODEL+speckle:SEED:IT, MODEL+patches:SEED:IT).

Not part of the test suite (minutes per seed); compare two runs' --out files with --compare.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

import bench.repair as bench_repair
from algorithms import cases as gen
from algorithms.mesh import Mesh
from algorithms.topology import edge_table
from bench.cases import DATA, BenchCase, ball, load, slab
from bench.repair import angle_target, meshlib_fill, ours_repair, run_isolated, score

# trimesh's own primitives, slivers and all: name -> (builder of trimesh's module, genus)
TRIMESH = {
    "capsule": (lambda t: t.creation.capsule(height=2.0, radius=0.6, count=[48, 48]), 0),
    # a thick washer: genus 1 with four sharp circular creases
    "annulus": (lambda t: gen.subdivided(t.creation.annulus(r_min=0.5, r_max=1.2, height=0.6, sections=96), 2), 1),
    # side triangles as long as the cylinder, caps fans of slivers
    "cylinder": (lambda t: t.creation.cylinder(radius=0.5, height=1.5, sections=64), 0),
    # the same, subdivided twice: its rims polygons with straight runs
    "cylinder-sub": (lambda t: gen.subdivided(t.creation.cylinder(radius=0.5, height=1.5, sections=48), 2), 0),
    # flat faces and sharp right-angled edges, subdivided four times
    "box": (lambda t: gen.subdivided(t.creation.box((1.0, 0.7, 0.4)), 4), 0),
    "icosphere": (lambda t: t.creation.icosphere(4), 0),
    "uv-sphere": (lambda t: t.creation.uv_sphere(radius=0.7, count=[32, 32]), 0),  # poles where 32 slivers meet
    # 48 slivers from the apex to a sharp rim, the base a fan
    "cone": (lambda t: t.creation.cone(radius=0.5, height=1.0, sections=48), 0),
    # the box subdivided once: big faces, a cut takes whole ones
    "box-coarse": (lambda t: gen.subdivided(t.creation.box((1.0, 0.7, 0.4)), 1), 0),
    # an octagonal prism: a side is two triangles, its edges 45 degrees sharp
    "prism-8": (lambda t: t.creation.cylinder(radius=0.5, height=1.0, sections=8), 0),
    # a fat tube (radii 1 and 0.6): the hole through it is small
    "torus-thick": (lambda t: t.creation.torus(1.0, 0.6, major_sections=48, minor_sections=32), 1),
    # trimesh's default torus (radii 1 and 0.35, 64 x 24): a slim tube of near-equilateral faces
    "torus-trimesh": (lambda t: t.creation.torus(1.0, 0.35, major_sections=64, minor_sections=24), 1),
    # 80 faces: a cut takes a few big faces of a coarse curved surface
    "icosphere-80": (lambda t: t.creation.icosphere(1), 0),
    # profiles revolved about z (64 sections, subdivided twice): a vase with a narrow neck, and a
    # mushroom whose cap overhangs its stem
    "vase": (lambda t: gen.subdivided(t.creation.revolve(
        [[0, 0], [0.5, 0], [0.6, 0.3], [0.55, 0.8], [0.2, 1.2], [0.18, 1.5], [0.3, 1.7], [0, 1.7]],
        sections=64), 2), 0),
    "mushroom": (lambda t: gen.subdivided(t.creation.revolve(
        [[0, 0], [0.25, 0], [0.22, 0.8], [0.9, 0.85], [0.85, 1.05], [0.5, 1.3], [0, 1.35]], sections=64), 2), 0),
}


def trimesh_model(kind: str) -> Mesh:
    """One of trimesh's primitives (``TRIMESH``), slivers and all (a capsule's side is one row of
    triangles as long as the capsule; the annulus' flat rings are fans of thin triangles): holes
    whose borders mix short and long edges."""
    import trimesh

    if kind not in TRIMESH:
        raise ValueError(f"unknown trimesh model {kind!r}")
    m = TRIMESH[kind][0](trimesh)
    return Mesh(np.asarray(m.vertices, float), np.asarray(m.faces, np.int64))


def _peanut() -> Mesh:
    """A sphere stretched along x and pinched at its middle (genus 0, saddle-shaped waist)."""
    m = gen.icosphere(5)
    v = m.vertices.copy()
    x = v[:, 0]
    v[:, 1:] *= (0.55 + 0.45 * x**2)[:, None]
    v[:, 0] *= 1.8
    return Mesh(v, m.faces)


def _flat_torus() -> Mesh:
    """A torus whose tube is an ellipse twice as wide as high (genus 1)."""
    m = gen.torus(1.0, 0.3, 96, 32)
    v = m.vertices.copy()
    r = np.hypot(v[:, 0], v[:, 1])
    scale = (1.0 + 1.0 * (r - 1.0) / r)[:, None]  # stretch the tube radially about its centre circle
    v[:, :2] *= scale
    return Mesh(v, m.faces)


def _hole(cx: float, radius: float = 0.18) -> str:
    """Outside a vertical cylinder at (cx, 0): a round through-hole where it is and-ed."""
    return f"((x-{cx})**2 + y**2 - {radius}**2)"


def _tube(cx: float, major: float = 0.45, minor: float = 0.17) -> str:
    return f"({minor}**2 - (sqrt((x-{cx})**2 + y**2) - {major})**2 - z**2)"


# F-rep objects (text, bounds), triangulated like the demo objects: of genus 2 and 3, handles side
# by side, and a thin tube round a figure eight (the lemniscate (x^2 + y^2)^2 = x^2 - y^2), whose
# cuts often take a whole piece of the tube; and thin walls, narrow bars and saddles
FREP_EXTRA = {
    "dtorus": (f"r_or({_tube(-0.42)}, {_tube(0.42)})", ((-1.1, -0.7, -0.3), (1.1, 0.7, 0.3))),
    "ttorus": (f"r_or(r_or({_tube(-0.84)}, {_tube(0.0)}), {_tube(0.84)})", ((-1.5, -0.7, -0.3), (1.5, 0.7, 0.3))),
    "lemni": ("0.012 - ((x**2 + y**2)**2 - x**2 + y**2)**2 - z**2", ((-1.2, -0.6, -0.2), (1.2, 0.6, 0.2))),
    # added after the sheet rule (repair_field.through_sheet) was made on a thin plate: a plate with
    # three round through-holes, a bowl (a hemispherical shell 0.15 thick), two balls on a bar,
    # three rods crossing
    "plate3": ("r_and(r_and(r_and(1 - x**2, 0.36 - y**2), 0.0225 - z**2), r_and(r_and("
               f"{_hole(-0.55)}, {_hole(0.0)}), {_hole(0.55)}))", ((-1.1, -0.7, -0.2), (1.1, 0.7, 0.2))),
    "bowl": ("r_and(r_and(1 - x**2 - y**2 - z**2, x**2 + y**2 + z**2 - 0.85**2), -z)",
             ((-1.1, -1.1, -1.1), (1.1, 1.1, 0.1))),
    "dumbbell": ("r_or(r_or(0.16 - (x-0.7)**2 - y**2 - z**2, 0.16 - (x+0.7)**2 - y**2 - z**2), "
                 "r_and(0.0225 - y**2 - z**2, 0.64 - x**2))", ((-1.2, -0.5, -0.5), (1.2, 0.5, 0.5))),
    "cross": ("r_or(r_or(r_and(0.04 - y**2 - z**2, 0.81 - x**2), r_and(0.04 - x**2 - z**2, 0.81 - y**2)), "
              "r_and(0.04 - x**2 - y**2, 0.81 - z**2))", ((-1, -1, -1), (1, 1, 1))),
}


def _frep(name: str) -> Mesh:
    """An F-rep object triangulated by our F-rep mesher (``bridgefield frep --demo NAME --qlev 6``):
    a bundled demo object, or one of ``FREP_EXTRA``. Smooth shapes no bench case is cut from
    (boxsphere has creases: a cube and a sphere joined by R-functions)."""
    from algorithms.frep.objects import demo_object, from_expression
    from algorithms.frep.pipeline import FrepParams, triangulate_object

    if name in FREP_EXTRA:
        text, bounds = FREP_EXTRA[name]
        obj = from_expression(text, name=name, bounds=bounds)
    else:
        obj = demo_object(name)
    return triangulate_object(obj, FrepParams(qlev=6)).mesh


# name -> (loader, genus)
MODELS = {
    "ellipsoid": (lambda: gen.ellipsoid((1.4, 1.0, 0.7), subdivisions=5), 0),
    "thin-torus": (lambda: gen.torus(1.0, 0.22, 96, 24), 1),
    "peanut": (_peanut, 0),
    "flat-torus": (_flat_torus, 1),
    **{name: (functools.partial(trimesh_model, name), genus) for name, (_, genus) in TRIMESH.items()},
    "fandisk": (lambda: load("fandisk.obj"), 0),
    "featuretype": (lambda: load("featuretype.stl"), 9),
    "torus": (lambda: load("torus.stl"), 1),
    "bunny": (lambda: load("bunny_closed.ply"), 0),
    # knotted tube (genus 1) and a star prism (flat faces, convex and concave sharp edges): shapes
    # added after the rules were made, to be cut as unseen ones
    "trefoil": (lambda: gen.trefoil_tube(), 1),
    "star": (lambda: gen.star_prism(), 0),
    # a thin plate (3 x 2 x 0.12): a ball takes both sides (the sheet rule's shape, repair_field.through_sheet)
    "thin-plate": (lambda: gen.plate((3.0, 2.0, 0.12)), 0),
    **{f"frep-{name}": (functools.partial(_frep, name), genus)
       for name, genus in (("blob", 0), ("perturbed", 0), ("boxsphere", 0), ("torus", 1),
                           ("dtorus", 2), ("ttorus", 3), ("lemni", 2), ("plate3", 3), ("bowl", 0),
                           ("dumbbell", 0), ("cross", 0))},
}


STYLES = ("balls", "cross", "speckle", "patches")  # how make_cut removes faces (a cut not by balls is named so)


def geodesic_patches(mesh: Mesh, seeds: list[int], radii: list[float]) -> NDArray[np.bool_]:
    """Faces whose centroid lies within ``radii[k]`` of vertex ``seeds[k]`` for some k, measured
    over the surface (shortest paths along the edges, then on to the centroid): holes that stay on
    their side of a thin wall, as a scanner's occlusions do, where a ball takes both sides."""
    V, F = mesh.vertices, mesh.faces
    e = edge_table(F).edges
    g = coo_matrix((np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1), (e[:, 0], e[:, 1])),
                   shape=(len(V), len(V))).tocsr()
    to_corner = np.linalg.norm(V[F] - gen.face_centroids(mesh)[:, None], axis=2)
    out = np.zeros(len(F), dtype=bool)
    for seed, radius in zip(seeds, radii):  # one search per disk, each within its own radius
        d = dijkstra(g, directed=False, indices=seed, limit=radius)
        out |= (d[F] + to_corner).min(axis=1) < radius  # through each corner to the centroid
    return out


def make_cut(model: str, seed: int, it: int, style: str = "balls") -> BenchCase:
    """One random cut.

    ``balls`` (the sweep's own, named MODEL:SEED:IT): 1-4 balls (radius 3-9 % of the diagonal) at
    random vertices, and with probability 1/2 a slab (width 1.5-3 %) through a random vertex.
    ``cross`` (MODEL+cross:SEED:IT): two slabs (width 1.5-3 %) through a point near the model's
    centre, at random normals at least 45 degrees apart: islands, and necks cut through.
    ``speckle`` (MODEL+speckle:SEED:IT): 2-8 % of the faces removed at random: many small holes,
    vertices where holes touch. ``patches`` (MODEL+patches:SEED:IT): 1-5 geodesic disks (radius
    4-15 % of the diagonal, measured over the surface) at random vertices: holes that stay on one
    side of a thin wall, merge where they overlap and can wrap a thin tube or a handle. 100 free
    points on the removed part with probability 1/2 (none for speckle)."""
    if style not in STYLES:
        raise ValueError(f"unknown cut style {style!r}: one of {', '.join(STYLES)}")
    truth = _model(model)
    genus = MODELS[model][1]
    d = truth.bbox_diagonal()
    tag = model if style == "balls" else f"{model}+{style}"
    rng = np.random.default_rng([seed, it, sum(map(ord, tag))])
    rm = np.zeros(truth.n_faces, dtype=bool)
    fp = 0
    if style == "balls":
        for _ in range(rng.integers(1, 5)):
            rm |= ball(truth, truth.vertices[rng.integers(truth.n_vertices)], rng.uniform(0.03, 0.09) * d)
        if rng.random() < 0.5:
            n = rng.normal(size=3)
            p = truth.vertices[rng.integers(truth.n_vertices)]
            rm |= slab(truth, n, float(p @ n / np.linalg.norm(n)), rng.uniform(0.015, 0.03) * d)
        fp = 100 if rng.random() < 0.5 else 0
    elif style == "cross":
        centre = truth.vertices.mean(axis=0) + rng.normal(scale=0.03 * d, size=3)
        n1 = rng.normal(size=3)
        n2 = rng.normal(size=3)
        while abs(n1 @ n2) > np.cos(np.radians(45)) * np.linalg.norm(n1) * np.linalg.norm(n2):
            n2 = rng.normal(size=3)
        for n in (n1, n2):
            rm |= slab(truth, n, float(centre @ n / np.linalg.norm(n)), rng.uniform(0.015, 0.03) * d)
        fp = 100 if rng.random() < 0.5 else 0
    elif style == "patches":
        draws = [(int(rng.integers(truth.n_vertices)), rng.uniform(0.04, 0.15) * d) for _ in range(rng.integers(1, 6))]
        rm |= geodesic_patches(truth, [x for x, _ in draws], [r for _, r in draws])
        fp = 100 if rng.random() < 0.5 else 0
    else:
        rm = rng.random(truth.n_faces) < rng.uniform(0.02, 0.08)
    c = gen.cut(truth, rm, name=f"{tag}:{seed}:{it}", description=f"random cut ({style})", free_points=fp, seed=seed)
    m = c.incomplete
    return BenchCase(c.name, np.asarray(m.vertices), np.asarray(m.faces), np.asarray(c.free_points), truth, genus,
                     c.description)


def hidden_handles(case: BenchCase) -> int:
    """Handles the cut took whole: the genus of the part of the truth the cut removed (its faces,
    split where pieces meet at a vertex only, as normalisation splits an input), summed over its
    pieces. Such a handle leaves no trace in the input's loops: a torus with a band across its tube
    removed keeps two facing loops (a tunnel), but a torus with the half that holds a handle removed
    keeps a disk and a ring whose loops say nothing of it (bench/sweep.py flat-torus:25:1: the removed
    half has genus 1; every filler that reads the loops caps it). A cut with hidden handles is
    scored like any other; the table counts them so that a miss there is read as what it is."""
    from algorithms.metrics import topology
    from algorithms.repair import _split_pinches

    truth = case.truth
    if truth is None:
        return 0
    at = {tuple(v): i for i, v in enumerate(np.asarray(truth.vertices))}  # the cut keeps the truth's coordinates
    to_truth = np.array([at.get(tuple(v), -1) for v in np.asarray(case.vertices)])
    kept = {tuple(sorted(f)) for f in to_truth[np.asarray(case.faces)].tolist()}
    removed = np.array([tuple(sorted(f)) not in kept for f in np.asarray(truth.faces).tolist()], dtype=bool)
    if not removed.any():
        return 0
    _, part, _ = _split_pinches(np.asarray(truth.vertices), np.asarray(truth.faces)[removed], 0)
    return int(round(topology(part).genus))


def cut_named(name: str) -> BenchCase:
    """The cut a name stands for: MODEL:SEED:IT (balls) or MODEL+STYLE:SEED:IT (``make_cut``)."""
    tag, seed, it = name.split(":")
    model, _, style = tag.partition("+")
    return make_cut(model, int(seed), int(it), style or "balls")


@functools.cache
def _model(name: str) -> Mesh:
    return MODELS[name][0]()


def _load(path: str) -> list[dict]:
    """The rows of an --out file."""
    return [json.loads(x) for x in Path(path).read_text().splitlines()]


def _seeds(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out += list(range(int(lo), int(hi or lo) + 1))
    return out


def _row_text(r: dict) -> str:
    if r["status"] != "ok":
        return f"{r['case']:<18} {r['method']:<8} {r['status']}: {r.get('note', '')}"
    g = "-" if r["genus"] is None else f"{r['genus']:g}"
    ang = r.get("unforced_min_angle")
    return (f"{r['case']:<18} {r['method']:<8} {'RIGHT' if r['topology_right'] else 'wrong':<5} "
            f"wt={'y' if r['watertight'] else 'n'} c={r['components']} g={g:<3} kept={r['kept']:.4f} "
            f"H={100 * r.get('hausdorff', float('nan')):6.2f}% ang={'-' if ang is None else f'{ang:5.1f}'} "
            f"t={r['seconds']:.2f}s")


def compare(old: str, new: str) -> None:
    """Print the rows whose topology, kept share or Hausdorff changed between two --out files."""
    def rows(p: str) -> dict:
        return {(r["case"], r["method"]): r for r in _load(p)}

    a, b = rows(old), rows(new)
    for k in sorted(set(a) & set(b)):
        x, y = a[k], b[k]
        fields = ("status", "topology_right", "genus", "kept")
        diff = [f"{f}: {x.get(f)} -> {y.get(f)}" for f in fields if x.get(f) != y.get(f)]
        hx, hy = x.get("hausdorff"), y.get("hausdorff")
        if hx is not None and hy is not None and abs(hx - hy) > 1e-4:
            diff.append(f"H: {100 * hx:.2f} -> {100 * hy:.2f} %")
        if diff:
            print(f"{k[0]:<18} {k[1]:<8} " + "; ".join(diff))
    for name, d in (("old", a), ("new", b)):
        ok = [r for k, r in d.items() if k in b and k in a]
        right = sum(bool(r.get("topology_right")) for r in ok)
        print(f"{name}: {right}/{len(ok)} topology right")


RATIO_FLOOR = 1e-4  # of the diagonal: the least MeshLib distance a ratio divides by


def markdown(rows: list[dict], command: str) -> str:
    """The sweep's section of docs/benchmarks.md: per model and method, the cuts whose output is a
    closed manifold (watertight, one component), whose topology is right, that keep every input
    face; Hausdorff (median and worst) and its ratio to MeshLib's on the same cut."""
    from bench.report import table

    by_cut: dict[str, dict[str, dict]] = {}
    for r in rows:
        by_cut.setdefault(r["case"], {})[r["method"]] = r
    models = sorted({c.split(":")[0] for c in by_cut}, key=lambda m: (list(MODELS).index(m.partition("+")[0]), m))
    methods = [m for m in ("light", "full", "meshlib") if any(m in d for d in by_cut.values())]
    out = []
    for model in models:
        cuts = {c: d for c, d in by_cut.items() if c.startswith(model + ":")}
        for m in methods:
            got = [d[m] for d in cuts.values() if m in d]
            ok = [r for r in got if r["status"] == "ok"]
            closed = sum(bool(r["watertight"]) and r["components"] == 1 for r in ok)
            right = sum(bool(r["topology_right"]) for r in ok)
            kept = sum(r["kept"] >= 1.0 for r in ok)
            h = np.array([r["hausdorff"] for r in ok if r.get("hausdorff") is not None])
            # MeshLib's distance floored at RATIO_FLOOR: where its fill is exact (a flat cut of a
            # cylinder's side), a ratio to 1e-9 says nothing
            ratio = np.array([d[m]["hausdorff"] / max(d["meshlib"]["hausdorff"], RATIO_FLOOR) for d in cuts.values()
                              if m != "meshlib" and m in d and "meshlib" in d and d[m].get("hausdorff") is not None
                              and d["meshlib"].get("hausdorff") is not None])
            out.append([model, m, len(got), f"{closed}/{len(got)}", f"{right}/{len(got)}", f"{kept}/{len(got)}",
                        f"{100 * np.median(h):.2f}" if len(h) else "–", f"{100 * h.max():.2f}" if len(h) else "–",
                        f"{np.median(ratio):.2f}" if len(ratio) else "–", f"{ratio.max():.2f}" if len(ratio) else "–",
                        int((ratio <= 0.5).sum()) if len(ratio) else "–",
                        f"{sum(angle_target(r, unforced=True) for r in ok)}/{len(got)}"])
    head = ["model", "method", "cuts", "closed, 1 piece", "topology right", "every face kept",
            "Hausdorff median %", "worst %", "÷ MeshLib median", "÷ MeshLib worst", "cuts ≤ ½ MeshLib",
            "patch angles on target"]
    return "\n".join([
        "## Repair on random cuts (`python -m bench.sweep`)", "",
        f"`{command}`: each model cut by 1-4 balls of faces (radius 3-9 % of the diagonal), half of the "
        "time also a slab (width 1.5-3 %), half of the time with 100 free points sampled on the removed "
        "part; cuts named MODEL:SEED:IT (`--only` re-runs one; with `--styles cross,speckle` also two "
        "slabs crossing near the model's centre, MODEL+cross, and 2-8 % of the faces at random, "
        "MODEL+speckle; with `--styles patches` 1-5 disks grown over the surface, MODEL+patches). "
        "No bench case is among them and none was "
        "looked at while the rules were made, except the ones the tests name (tests/test_repair_random_cuts.py, "
        "test_repair_sheets.py, test_repair_rims.py), the thin-plate cuts the sheet rule was made on "
        "(repair_field.through_sheet), the turned-part cuts the rim rules were traced on (darning/sheets.py, "
        "refine._move_best), the mushroom, featuretype and trefoil cuts the crease circles and facing rims "
        "were traced on (creases.crease_ends, repair_field._between) and the annulus, mushroom, featuretype and "
        "frep-plate3 cuts the fine-rim walk was traced on (creases.CreaseEnds.at), and the frep-boxsphere cuts "
        "the convex clamp was traced on (darning/convex.py); each then checked on the "
        "whole sweep. "
        "Scored as the repair benchmark scores (topology with the vertices at one position merged, as the "
        "scorer loads an output; Hausdorff in % of the model's diagonal, sampled); "
        "\"light\"/\"full\": our repair, \"meshlib\": MeshLib's bridgeFillAllHoles on the same cut; "
        f"in the ratios MeshLib's distance counts as at least {100 * RATIO_FLOOR:g} % (it is exact on some cuts). "
        "Patch angles on target: the issue's bound (no angle below 15°, under 5 % below 20°) over the angles "
        "that some fill could avoid, as in the repair benchmark's unforced columns (`bench.repair.angle_target`).",
        "", table(head, out)] + _hidden_note(by_cut, methods))


def _hidden_note(by_cut: dict[str, dict[str, dict]], methods: list[str]) -> list[str]:
    """A line under the table: the cuts that took a handle whole (``hidden_handles``, read from
    rows that have it) and how each method did there; nothing for rows without it."""
    known = {c: d for c, d in by_cut.items() if any("hidden_handles" in r for r in d.values())}
    hidden = [d for d in known.values() if any(r.get("hidden_handles") for r in d.values())]
    if not known:
        return []
    right = ", ".join(f"{m} {sum(bool(d[m].get('topology_right')) for d in hidden if m in d)}" for m in methods)
    return ["", f"Cuts that took a handle whole (the removed part has genus > 0, `bench.sweep.hidden_handles`: "
                f"no pair of the input's loops carries it): {len(hidden)} of {len(known)}"
                + (f"; topology right there: {right}." if hidden else ".")]


def _command(a: argparse.Namespace) -> str:
    """The command that makes these rows (for the table's text)."""
    models = "" if a.models == ",".join(MODELS) else f" --models {a.models}"
    styles = "" if a.styles == "balls" else f" --styles {a.styles}"
    return f"python -m bench.sweep --seeds {a.seeds} --per-seed {a.per_seed}{models}{styles} --write"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.sweep", description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="1-10", help="seeds, e.g. 1-5 or 1,4")
    ap.add_argument("--per-seed", type=int, default=2, help="cuts per model and seed")
    ap.add_argument("--models", default=",".join(MODELS), help="comma-separated: " + ", ".join(MODELS))
    ap.add_argument("--modes", default="light,full", help="our modes ('' for the peers only)")
    ap.add_argument("--peers", default="meshlib", help="'meshlib' or '' (none)")
    ap.add_argument("--styles", default="balls", help="cut styles, comma-separated: " + ", ".join(STYLES))
    ap.add_argument("--only", help="these cuts only, MODEL[+STYLE]:SEED:IT[,...]")
    ap.add_argument("--save", help="write each cut as DIR/MODEL_SEED_IT.npz")
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--out", help="append the rows as JSON lines here")
    ap.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"), help="compare two --out files and exit")
    ap.add_argument("--write", action="store_true", help="write the summary to docs/benchmarks.md (section sweep)")
    ap.add_argument("--from-json", help="only write the summary of rows saved with --out (needs --write)")
    a = ap.parse_args(argv)
    if a.compare:
        compare(*a.compare)
        return 0
    if a.from_json:
        from bench.report import write_section

        text = markdown(_load(a.from_json), _command(a))
        if a.write:
            write_section("sweep", text)
        print(text)
        return 0
    if not DATA.exists():
        print(f"sweep: {DATA} not found (the shared models)", file=sys.stderr)
        return 2
    if a.only:
        todo = a.only.split(",")
    else:
        todo = [f"{m if style == 'balls' else f'{m}+{style}'}:{s}:{i}" for style in a.styles.split(",")
                for s in _seeds(a.seeds) for m in a.models.split(",") for i in range(a.per_seed)]
    methods = {f"ours-{mode}": (lambda V, F, P, mode=mode: ours_repair(V, F, P, mode))
               for mode in a.modes.split(",") if mode}  # --modes '': the peers only
    if a.peers == "meshlib":
        methods["meshlib"] = lambda V, F, P: meshlib_fill(V, F, P, "bridge")
    import algorithms.repair  # noqa: F401  (imported once here: every forked run uses the same code)

    bench_repair.REPEAT_BELOW = 0.0  # one run per tool: a sweep measures outcomes, bench/repair.py times
    out = open(a.out, "a") if a.out else None
    rows: list[dict] = []
    for name in todo:
        case = cut_named(name)
        if a.save:
            Path(a.save).mkdir(parents=True, exist_ok=True)
            np.savez(Path(a.save) / f"{case.name.replace(':', '_')}.npz", vertices=case.vertices, faces=case.faces,
                     free_points=case.free_points, truth_vertices=case.truth.vertices, truth_faces=case.truth.faces,
                     genus=case.genus)
        hidden = hidden_handles(case)
        for label, fn in methods.items():
            status, got = run_isolated(fn, case, a.timeout)
            row = {"case": case.name, "method": label.removeprefix("ours-"), "status": status, "hidden_handles": hidden}
            if status == "ok":
                V2, F2, dt = got
                row.update(score(case, V2, F2, samples=a.samples), seconds=dt)
            else:
                row["note"] = str(got)
            print(_row_text(row), flush=True)
            rows.append(row)
            if out:
                out.write(json.dumps(row) + "\n")
                out.flush()
    if a.write:
        from bench.report import write_section

        write_section("sweep", markdown(rows, _command(a)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

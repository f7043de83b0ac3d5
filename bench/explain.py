"""Why a sweep cut comes back the way it does: its islands and loops (after normalisation, as the
repair sees them), the force lines between the
loops, the bridges kept and refused, the facing-rims measures of the loop pairs the rules read
(``rim_table``), and where the output is farthest from the truth, loop by loop.

    python -m bench.explain MODEL[+STYLE]:SEED:IT [--mode light|full] [--meshlib] [--samples N]

The cut is made as ``bench.sweep`` makes it (``cut_named``). Loops are numbered as the repair
numbers them (``boundary.summarize``: the order of its frames), so the report's tunnel notes
("loops 2 and 3: ...") read against the table. For each loop, the largest distance from the
truth to the output over the truth's points nearest to that loop (of all loops), in % of the
diagonal: the hole whose fill (or missing tube) is off; and the largest distance from the output
to the truth over the output's points nearest to it: a fill that sticks out. ``--meshlib``: the
same for MeshLib's bridge fill (the ``[bench]`` extra). Not part of the test suite; a debugging aid
for the sweep's misses.
"""

from __future__ import annotations

import argparse
import re
from collections import Counter, defaultdict

import numpy as np
from scipy.spatial import cKDTree

from algorithms.boundary import summarize
from algorithms.metrics import distance_samples
from algorithms.normalize import normalize
from algorithms.params import FieldParams
from algorithms.repair import RepairParams, RepairResult, repair
from bench.cases import BenchCase
from bench.repair import merge_positions


def line_table(res: RepairResult, loop_of: dict[int, int]) -> dict[tuple[int, int], list[float]]:
    """Arrived force lines by (start loop, end loop) (-1: not at a loop vertex), qualities best first."""
    out: dict[tuple[int, int], list[float]] = defaultdict(list)
    for ln in res.lines:
        if ln.arrived:
            key = (loop_of.get(int(ln.start_vertex), -1), loop_of.get(int(ln.end_vertex), -1))
            out[key].append(float(ln.quality))
    return {k: sorted(v, reverse=True) for k, v in sorted(out.items())}


def bridge_table(res: RepairResult, loop_of: dict[int, int]) -> Counter:
    """Kept bridges by (kind, loop of its start, loop of its end) (-1: a vertex of no input loop)."""
    return Counter((b.kind, loop_of.get(int(b.start), -1), loop_of.get(int(b.end), -1)) for b in res.bridges)


def refusal_table(res: RepairResult, loop_of: dict[int, int]) -> dict[tuple[int, int], Counter]:
    """Refused candidates by the (sorted) pair of loops their line joins, counted by reason (the
    vertices of the bridge a reason names left out)."""
    out: dict[tuple[int, int], Counter] = defaultdict(Counter)
    for idx, why in res.rejected:
        if not 0 <= idx < len(res.lines) or not res.lines[idx].arrived:
            continue
        ln = res.lines[idx]
        a, b = loop_of.get(int(ln.start_vertex), -1), loop_of.get(int(ln.end_vertex), -1)
        out[(min(a, b), max(a, b))][re.sub(r"\d+-\d+", "…", why)] += 1  # bridge 12-34: one reason
    return dict(sorted(out.items()))


def rim_table(frames: list, lines: dict[tuple[int, int], list[float]]) -> list[dict]:
    """The facing-rims measures (``repair_field.facing_rims``) of the loop pairs the rules may read:
    pairs joined by an arrived line, and pairs of loops both steep enough for the slanted test. Per
    pair (a < b): mean |n . N| of each (``rim_axis``), mean b . u of each towards the other, |N . u|
    of each, centroid distance, mean radii, and which tests pass (square, slanted; of one island or
    of two, with ``_between``'s verdict)."""
    import algorithms.repair_field as rf

    geo = {k: rf.rim_axis(f) for k, f in enumerate(frames)}  # every loop: _between reads the others too
    joined = {(min(a, b), max(a, b)) for a, b in lines if a >= 0 and b >= 0 and a != b}
    out = []
    for a in range(len(frames)):
        for b in range(a + 1, len(frames)):
            steep = geo[a][2] < rf.SLANT_RIM and geo[b][2] < rf.SLANT_RIM
            if (a, b) not in joined and not steep:
                continue
            d = geo[b][0] - geo[a][0]
            dist = float(np.linalg.norm(d))
            u = d / dist if dist > 0 else d
            one = frames[a].island == frames[b].island
            tests = {"square": (a, b) in rf.facing_rims(frames, [a, b], same_island=one),
                     "slanted": (a, b) in rf.slanted_rims(frames, [a, b], same_island=one)}
            out.append({"pair": (a, b), "same_island": one, "rim": (geo[a][2], geo[b][2]),
                        "facing": (float((frames[a].outward @ u).mean()), float((frames[b].outward @ -u).mean())),
                        "across": (abs(float(geo[a][1] @ u)), abs(float(geo[b][1] @ u))), "distance": dist,
                        "radii": (rf.loop_radius(frames[a]), rf.loop_radius(frames[b])),
                        "between": rf._between(frames, geo, a, b), **tests})
    return out


def worst_by_loop(case: BenchCase, V: np.ndarray, F: np.ndarray, loops: list[np.ndarray], *,
                  samples: int = 20000) -> list[tuple[float, float]]:
    """Per loop: the largest distance (% of the truth's diagonal) from the truth to the output and
    from the output to the truth, each over the points nearest to that loop's vertices (of all
    loops): a fill that misses the surface, and one that sticks out of it. The points are those the
    score measures (``metrics.distance_samples`` on the output merged by position, as
    ``bench.repair.score`` does), so the largest of all is the score's Hausdorff distance."""
    diag = case.truth.bbox_diagonal()
    mv, mf = merge_positions(V, F, 1e-6 * diag)
    pm, d_out, pr, d_in = distance_samples(mv, mf, case.truth.vertices, case.truth.faces, samples=samples)
    owner = np.concatenate([np.full(len(lp), k) for k, lp in enumerate(loops)])
    tree = cKDTree(np.vstack([case.vertices[lp] for lp in loops]))
    worst = np.zeros((len(loops), 2))
    for side, (pts, d) in enumerate(((pr, d_in), (pm, d_out))):
        np.maximum.at(worst[:, side], owner[tree.query(pts)[1]], 100 * d / diag)
    return [(float(x), float(y)) for x, y in worst]


def explain(name: str, mode: str = "light", *, meshlib: bool = False, samples: int = 20000) -> dict:
    """Everything the text report prints, as a dict (see the module's docstring)."""
    from bench.repair import meshlib_fill, score
    from bench.sweep import cut_named, hidden_handles

    case = cut_named(name)
    model = normalize(case.vertices, case.faces, extra_points=case.free_points)
    summary = summarize(model)
    frames = list(summary.loops)
    loop_of = {int(v): k for k, f in enumerate(frames) for v in f.vertices}
    res = repair(model, RepairParams(field=FieldParams(mode=mode)))
    V, F = np.asarray(res.mesh.vertices), np.asarray(res.mesh.faces)
    # loops as vertices of the cut (normalisation keeps the input's vertex order for referenced ones)
    origin = model.vertex_origin if model.vertex_origin is not None else np.arange(model.mesh.n_vertices)
    loops = [np.asarray(origin[f.vertices]) for f in frames]
    out = {
        "name": name, "mode": mode, "genus": case.genus, "free_points": int(len(case.free_points)),
        "set_aside": len(model.set_aside), "hidden_handles": hidden_handles(case),
        "islands": [{"island": i.index, "faces": i.faces, "euler": i.euler, "loops": len(i.loops), "genus": i.genus}
                    for i in summary.islands],
        "loops": [{"loop": k, "island": int(f.island), "vertices": int(len(f.vertices)),
                   "centre": [round(float(x), 3) for x in f.points.mean(axis=0)],
                   "radius": round(float(np.linalg.norm(f.points - f.points.mean(axis=0), axis=1).mean()), 3)}
                  for k, f in enumerate(frames)],
        "lc": res.lc, "lines": line_table(res, loop_of), "bridges": bridge_table(res, loop_of),
        "refused": refusal_table(res, loop_of), "notes": res.tunnel_note, "class": res.class_found,
        "rims": rim_table(frames, line_table(res, loop_of)),
        "score": score(case, V, F, samples=samples),
        "worst": {"ours": worst_by_loop(case, V, F, loops, samples=samples)},
    }
    if meshlib:
        mv, mf = meshlib_fill(case.vertices, case.faces, case.free_points, "bridge")
        out["score_meshlib"] = score(case, mv, mf, samples=samples)
        out["worst"]["meshlib"] = worst_by_loop(case, mv, mf, loops, samples=samples)
    return out


def text(r: dict) -> str:
    s = r["score"]
    lines = [f"{r['name']} ({r['mode']}): truth genus {r['genus']}, {r['free_points']} free points, "
             f"{r['set_aside']} faces set aside; class {r['class']}, L_c {r['lc']:.3g}"
             + (f"; the cut took {r['hidden_handles']} handle(s) whole (no pair of loops carries them)"
                if r.get("hidden_handles") else ""),
             f"ours: topology {'right' if s['topology_right'] else 'WRONG'} (watertight {s['watertight']}, "
             f"components {s['components']}, genus {s['genus']}), Hausdorff {100 * (s.get('hausdorff') or 0):.2f} %"]
    if "score_meshlib" in r:
        m = r["score_meshlib"]
        lines.append(f"MeshLib: topology {'right' if m['topology_right'] else 'WRONG'} (genus {m['genus']}), "
                     f"Hausdorff {100 * (m.get('hausdorff') or 0):.2f} %")
    lines.append("islands:")
    lines += [f"  {i['island']}: {i['faces']} faces, Euler {i['euler']}, {i['loops']} loops, genus {i['genus']:g}"
              for i in r["islands"]]
    lines.append("loops (worst distance near each, truth -> output and output -> truth, %"
                 + (": ours / MeshLib)" if "meshlib" in r["worst"] else ")") + ":")
    for lp in r["loops"]:
        k = lp["loop"]
        w = " / ".join(f"{r['worst'][who][k][0]:.2f}, {r['worst'][who][k][1]:.2f}" for who in ("ours", "meshlib")
                       if who in r["worst"])
        lines.append(f"  {k}: island {lp['island']}, {lp['vertices']} vertices, centre {lp['centre']}, "
                     f"radius {lp['radius']}; worst {w}")
    lines.append("arrived lines (start loop -> end loop: count, best qualities):")
    lines += [f"  {a} -> {b}: {len(q)}, {', '.join(f'{x:.3g}' for x in q[:6])}" for (a, b), q in r["lines"].items()]
    lines.append("bridges kept (kind, loop, loop: count):")
    lines += [f"  {kind} {a}-{b}: {n}" for (kind, a, b), n in sorted(r["bridges"].items())]
    lines.append("refused (loop pair: reasons):")
    for (a, b), reasons in r["refused"].items():
        lines.append(f"  {a}-{b}: " + "; ".join(f"{n} x {why}" for why, n in reasons.most_common(4)))
    if r.get("rims"):
        lines.append("rims (pairs joined by a line or both steep: mean |n . N|, facing, across, distance, radii):")
        lines += [f"  {x['pair'][0]}-{x['pair'][1]}{'' if x['same_island'] else ' (two islands)'}: "
                  f"{x['rim'][0]:.2f} / {x['rim'][1]:.2f}, {x['facing'][0]:.2f} / {x['facing'][1]:.2f}, "
                  f"{x['across'][0]:.2f} / {x['across'][1]:.2f}, {x['distance']:.3g}, "
                  f"{x['radii'][0]:.3g} / {x['radii'][1]:.3g}"
                  + "".join(f"; {t}" for t in ("square", "slanted") if x[t])
                  + ("; a rim between" if x["between"] else "") for x in r["rims"]]
    if r["notes"]:
        lines.append("notes: " + r["notes"])
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.explain", description=__doc__.split("\n\n")[0])
    ap.add_argument("cut", help="MODEL[+STYLE]:SEED:IT, as bench.sweep names its cuts")
    ap.add_argument("--mode", choices=("light", "full"), default="light")
    ap.add_argument("--meshlib", action="store_true", help="also MeshLib's bridge fill (the [bench] extra)")
    ap.add_argument("--samples", type=int, default=20000)
    a = ap.parse_args(argv)
    print(text(explain(a.cut, a.mode, meshlib=a.meshlib, samples=a.samples)))
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

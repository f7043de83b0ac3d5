"""Benchmark: `bridgefield hybrid` against Gmsh on the paper's two surfaces (spec/hybrid.md §5).

Run: python -m bench.hybrid [--sizes 1000 5000 20000] [--surfaces bezier-hole interstage dome]

Both meshers get the same surface: Gmsh through OpenCASCADE (the Bezier patch from the same
control points, cut by the r = 0.4 cylinder along Ox; the cone cut by the same openings built as
solids: rounded-rectangle prisms and a cylinder, rotated by alpha_i about Oy, the z_i-limited
ones extruded from the axis outwards). Each mesher's size parameter is tuned to land near the
target triangle count (ours: the chordal tolerance max_deviation). Chordal deviation: the distance
from the centroids and edge midpoints of the mesh triangles to the exact surface R(u, v) (closest
point by Gauss-Newton from the nearest point of a dense sample), relative to the model size; reported as max and mean.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from dataclasses import replace

import numpy as np
from scipy.spatial import cKDTree

from algorithms.demos import demo
from algorithms.hybrid.mesher import mesh_hybrid
from algorithms.hybrid.spec import load_spec
from algorithms.metrics import angle_stats, min_angles, topology

from .report import table, write_section


# ---- Gmsh models -----------------------------------------------------------------------------------
def gmsh_bezier(gmsh, data: dict) -> list[int]:
    occ = gmsh.model.occ
    P = np.array(data["surface"]["control"], dtype=float)  # (i: u, j: v)
    n_u = P.shape[0]
    tags = [occ.addPoint(*P[i, j]) for j in range(P.shape[1]) for i in range(n_u)]  # u fastest
    s = occ.addBezierSurface(tags, n_u)
    r = float(data["constants"]["r"])
    cyl = occ.addCylinder(-1, 0, 0, 7, 0, 0, r)
    out, _ = occ.cut([(2, s)], [(3, cyl)])
    occ.synchronize()
    return [t for d, t in out if d == 2]


def gmsh_interstage(gmsh, data: dict) -> list[int]:
    from algorithms.expr import compile_expr

    occ = gmsh.model.occ
    consts: dict[str, float] = {}
    for k, v in data["constants"].items():
        consts[k] = float(v) if isinstance(v, (int, float)) else \
            float(compile_expr(v, variables=(), constants=consts)())
    c = consts
    L = c["l"]
    cone = occ.addCone(0, 0, 0, 0, L, 0, c["r_bottom"], c["r_top"])
    occ.synchronize()
    walls = gmsh.model.getBoundary([(3, cone)], oriented=False)
    occ.remove([(3, cone)])
    lateral = None
    for _d, t in walls:  # keep the conical face, drop the two caps
        x0, y0, z0, x1, y1, z1 = occ.getBoundingBox(2, t)
        if y1 - y0 > 1e-6:
            lateral = t
        else:
            occ.remove([(2, t)], recursive=True)
    big = 5.0

    def opening(w, h, r, y0, alpha, half, circle=False):
        if circle:
            z0 = 0.0 if half else -big
            tag = occ.addCylinder(0, y0, z0, 0, 0, big - z0, r)
        else:
            z0 = 0.0 if half else -big
            rect = occ.addRectangle(-w / 2, y0 - h / 2, z0, w, h, roundedRadius=r)
            ext = occ.extrude([(2, rect)], 0, 0, big - z0)
            tag = [t for d, t in ext if d == 3][0]
        occ.rotate([(3, tag)], 0, 0, 0, 0, 1, 0, -alpha)  # x_i = x cos a + z sin a  (§5)
        return (3, tag)

    tools = [
        opening(c["a1"], c["a1"], c["r1"], c["h1"], c["al1"], False),
        opening(c["a1"], c["a1"], c["r1"], c["h1"], c["al2"], False),
        opening(c["a1"], c["a2"], c["r2"], c["h2"], c["al3"], False),
        opening(c["a3"], c["a4"], c["r3"], c["h4"], c["al4"], True),
        opening(c["a5"], c["a6"], c["r4"], c["h4"], c["al5"], True),
        opening(c["a7"], c["a8"], c["r5"], c["h5"], c["al6"], True),
        opening(0, 0, c["r6"], c["h3"], c["al7"], True, circle=True),
    ]
    out, _ = occ.cut([(2, lateral)], tools)
    occ.synchronize()
    return [t for d, t in out if d == 2]


def gmsh_mesh(name: str, data: dict, h: float, algorithm: int) -> tuple[np.ndarray, np.ndarray, float]:
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        faces = gmsh_bezier(gmsh, data) if data["surface"]["type"] == "bezier" else gmsh_interstage(gmsh, data)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        gmsh.option.setNumber("Mesh.Algorithm", algorithm)
        t0 = time.perf_counter()
        gmsh.model.mesh.generate(2)
        dt = time.perf_counter() - t0
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        idx = {int(t): i for i, t in enumerate(node_tags)}
        X = coords.reshape(-1, 3)
        tris = []
        for f in faces:
            types, _, enodes = gmsh.model.mesh.getElements(2, f)
            for ty, en in zip(types, enodes):
                if ty == 2:
                    tris.append(np.array([idx[int(x)] for x in en]).reshape(-1, 3))
        F = np.vstack(tris)
        return X, F, dt
    finally:
        gmsh.finalize()


# ---- chordal deviation ----------------------------------------------------------------------------------
def chordal(surface, V: np.ndarray, F: np.ndarray) -> tuple[float, float]:
    a, b, c, d = surface.domain
    U, W = np.meshgrid(np.linspace(a, b, 500), np.linspace(c, d, 500), indexing="ij")
    S = surface(U, W).reshape(-1, 3)
    tree = cKDTree(S)
    T = V[F]
    q = np.vstack([T.mean(1), 0.5 * (T[:, 0] + T[:, 1]), 0.5 * (T[:, 1] + T[:, 2]), 0.5 * (T[:, 2] + T[:, 0])])
    _, k = tree.query(q)
    u, v = U.ravel()[k], W.ravel()[k]
    for _ in range(8):  # Gauss-Newton: closest point on R(u, v)
        R = surface(u, v)
        ru, rv = surface.derivatives(u, v)
        r = R - q
        a11, a12, a22 = (ru * ru).sum(1), (ru * rv).sum(1), (rv * rv).sum(1)
        g1, g2 = (ru * r).sum(1), (rv * r).sum(1)
        det = a11 * a22 - a12 * a12
        du = -(a22 * g1 - a12 * g2) / det
        dv = -(-a12 * g1 + a11 * g2) / det
        u, v = np.clip(u + du, a, b), np.clip(v + dv, c, d)
    dist = np.linalg.norm(surface(u, v) - q, axis=1)
    size = surface.size
    return float(dist.max() / size), float(dist.mean() / size)


# ours twice: the border curve cut to the chordal tolerance too, or only as finely as Gmsh cuts its curves
# (chord / arc 0.97 is about Gmsh's default of 7 points a circle; encroachment splits the rest)
VARIANTS = (("border at the tolerance", {}),
            ("border by chord/arc 0.97", {"border_chord_arc": 0.97, "border_deviation": math.inf}))


# ---- the runs ----------------------------------------------------------------------------------------------
def tune(run, target: int, x0: float, power: float, tries: int = 6, tol: float = 0.1):
    """Run with parameter x until the triangle count is within tol (10 %) of target: the count goes about
    as x^power (power -2 for a length, -1 for a chordal tolerance), refined by a secant in log-log."""
    x = x0
    best = None
    seen: list[tuple[float, float]] = []
    for _ in range(tries):
        res = run(x)
        n = max(res[1], 1)
        if best is None or abs(n - target) < abs(best[1] - target):
            best = res
        if abs(n - target) <= tol * target:
            break
        seen.append((math.log(x), math.log(n)))
        slope = power
        if len(seen) >= 2:
            (x1, n1), (x2, n2) = seen[-2], seen[-1]
            if x2 != x1 and (n2 - n1) / (x2 - x1) < -0.2:
                slope = (n2 - n1) / (x2 - x1)
        x = math.exp(math.log(x) + (math.log(target) - math.log(n)) / slope)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 5000, 20000])
    ap.add_argument("--surfaces", nargs="+", default=["bezier-hole", "interstage", "dome"])
    ap.add_argument("--json", help="also write the rows as JSON")
    ap.add_argument("--no-doc", action="store_true", help="do not write docs/benchmarks.md")
    args = ap.parse_args(argv)
    rows: list[list] = []
    ratios: list[list] = []
    load0 = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"] * 3

    def flush() -> None:  # after every row, so an interrupted run still leaves its table
        headers = ["surface", "target", "mesher", "triangles", "min angle", "1st pct", "median", "<20° %", "<30° %",
                   "chordal max (rel.)", "chordal mean (rel.)", "boundary loops", "time s"]
        rheaders = ["surface", "target", "ours: border curve", "triangles", "chordal max / FD", "/ Delaunay",
                    "/ MeshAdapt", "time / FD", "/ Delaunay", "/ MeshAdapt", "ours re-run at"]
        load1 = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"] * 3
        body = ("## Hybrid surface meshing against Gmsh\n\n"
                "`python -m bench.hybrid` (bench/hybrid.py). Same surfaces for both: the paper's Bezier patch with "
                "the r = 0.4 hole, the interstage compartment and the dome (the Bezier patch with its interior "
                "control points pushed out: doubly curved), from assets/hybrid. Gmsh 4 through OpenCASCADE with a "
                "uniform size (MeshSizeMax tuned to our triangle count, no curvature sizing). Ours: min angle 30°, "
                "the curvature criterion in its chordal form (`max_deviation`, tuned to the target count; no "
                "max_edge, no chord/arc ratio), the default finishing (flip and smoothing passes, then coarsening: "
                "collapses that keep every bound, coarsen_angle 36°, median_floor 48.5°); two rows: the border "
                "curve also cut to that tolerance, or only as finely as Gmsh cuts its curves (chord/arc "
                "0.97, about Gmsh's 7 points a circle; the chordal error is measured against the surface, not "
                "the trim curve). Every count is tuned to "
                "within 10 % of its target where the tuning converges (the triangles column says). Angles in "
                "degrees over per-triangle minimum angles; chordal deviation: distance from triangle centroids and "
                "edge midpoints to the exact surface (closest point by Gauss-Newton) over the model size, the same "
                "code for both meshers; boundary loops of the output (the interstage must have 12: 10 openings, as "
                "the three through-hatches cut both sides, and the 2 rims, the seam welded). Times are wall-clock "
                "on a shared 2-core machine, the better of two runs; load average "
                f"{' '.join(load0)} at the start, {' '.join(load1)} at the last row: compare the ratios, measured "
                "in the same run, rather than the absolute times.\n\n" + table(headers, rows)
                + "\n\nRatios ours / Gmsh at the same triangle count (chordal max: below 0.5 is the issue's target; "
                "where Gmsh's count is more than 10 % off ours, as at 1k on the interstage, whose curves Gmsh cannot "
                "cut coarser, ours is re-run at Gmsh's count (within 3 %) for that ratio: last column; time: ours "
                "over Gmsh's meshing call, at the target):\n\n" + table(rheaders, ratios))
        if not args.no_doc:
            write_section("hybrid", body)

    for name in args.surfaces:
        path = demo(name, "hybrid").path
        spec = load_spec(path)
        data = json.loads(path.read_text())
        surf = spec.model.surface
        size = surf.size
        for target in args.sizes:
            ours_runs = []  # (label, n, cmax, time)
            for variant, extra in VARIANTS:
                def ours(eps, extra=extra):
                    base = {"max_edge": None, "chord_arc": 0.0, "border_chord_arc": 0.0, "max_deviation": eps}
                    p = replace(spec.params(), **{**base, **extra})
                    t0 = time.perf_counter()
                    r = mesh_hybrid(spec.model, p)
                    return (r, len(r.faces), time.perf_counter() - t0, eps)

                def run_ours(count, variant=variant, ours=ours, label_extra=""):
                    # at Gmsh's count (a re-run): within 3 %, tighter than the 10 % of the targets
                    r, n, dt, eps = tune(ours, count, 2.0 * size / count, -1.0, tries=8,
                                         tol=0.03 if label_extra else 0.1)
                    dt = min(dt, ours(eps)[2])  # the better of two timings: the machine is shared
                    st = r.stats_after
                    cmax, cmean = chordal(surf, r.points, r.faces)
                    rows.append([name, target, f"bridgefield, {variant}{label_extra} (max_deviation {eps / size:.3g}"
                                 " × size)", n, st.min, st.p01, st.median, 100 * st.below_20, 100 * st.below_30,
                                 cmax, cmean, topology(r.mesh.faces).boundary_loops, dt])
                    print(rows[-1], flush=True)
                    flush()
                    return n, cmax, dt

                ours_runs.append((variant, *run_ours(target), run_ours))
            n = ours_runs[0][1]
            gm = []
            h0 = math.sqrt(size ** 2 / 2) * math.sqrt(2.0 / n)
            for alg, label in ((6, "Gmsh Frontal-Delaunay"), (5, "Gmsh Delaunay"), (1, "Gmsh MeshAdapt")):
                def peer(hh, alg=alg):
                    X, F, t = gmsh_mesh(name, data, hh, alg)
                    return ((X, F), len(F), t, hh)

                (X, F), n2, dt2, h = tune(peer, n, h0, -2.0)
                dt2 = min(dt2, peer(h)[2])
                h0 = h
                st2 = angle_stats(min_angles(X, F))
                cmax2, cmean2 = chordal(surf, X, F)
                rows.append([name, target, label, n2, st2.min, st2.p01, st2.median, 100 * st2.below_20,
                             100 * st2.below_30, cmax2, cmean2, topology(F).boundary_loops, dt2])
                gm.append((cmax2, dt2, n2))
                print(rows[-1], flush=True)
                flush()
            for variant, n, cmax, dt, run_ours in ours_runs:
                # at the same triangle count: where Gmsh cannot come within 10 % of ours (its curves set a
                # floor), ours again at Gmsh's count
                same = {}
                for _c, _t, n2 in gm:
                    if abs(n2 - n) > 0.1 * n and n2 not in same:
                        same[n2] = run_ours(n2, label_extra=f", at Gmsh's {n2} triangles")
                ratios.append([name, target, variant, n]
                              + [(same[n2][1] if n2 in same else cmax) / c for c, _, n2 in gm]
                              + [dt / t for _, t, _ in gm]
                              + [", ".join(f"{k} triangles" for k in same) or "-"])
            flush()
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"rows": rows, "ratios": ratios}, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

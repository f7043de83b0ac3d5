"""`bridgefield hybrid SPEC -o OUT`: mesh a hybrid parametric + implicit surface (spec/hybrid.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..hybrid.mesher import mesh_hybrid
from ..hybrid.spec import load_spec
from ..io import OutputExistsError, check_output, save_mesh
from .common import add_input, input_path, write_json

NAME = "hybrid"
HELP = "mesh a parametric surface trimmed by an implicit function (Ruppert refinement on the surface)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_input(p, points=False, kind="hybrid")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="output mesh (PLY, OBJ, STL, OFF)")
    p.add_argument("--min-angle", type=float, metavar="A", help="min-angle threshold in degrees (default 30)")
    p.add_argument("--max-edge", type=float, metavar="H", help="longest 3D edge (default: the spec's)")
    p.add_argument("--chord-arc", type=float, metavar="R", help="curvature limit: chord / arc ratio (default 0.98)")
    p.add_argument("--max-deviation", type=float, metavar="E",
                   help="curvature limit as a chordal error: largest distance between the mesh and the surface "
                        "(and the border curve), in model units; sizes the mesh by curvature (h ∝ 1/√κ)")
    p.add_argument("--border-deviation", type=float, metavar="E",
                   help="the chordal tolerance for the border curve alone (default: --max-deviation; inf: off)")
    p.add_argument("--coarsen-angle", type=float, metavar="A",
                   help="after refinement, collapse the vertices the size criteria do not need while every new "
                        "triangle keeps at least this smallest angle (degrees, default 36; 0: no coarsening)")
    p.add_argument("--no-seed", action="store_true",
                   help="do not seed Stage III with the lattice along the rulings of cones and cylinders (it is "
                        "used with --max-deviation where the parameter lines are straight lines of curvature)")
    p.add_argument("--max-triangles", type=int, metavar="N", help="stop refining beyond N triangles")
    p.add_argument("--cells", type=int, metavar="N", help="Stage I background grid cells along the longer side")
    p.add_argument("--report", metavar="R.json", help="write the JSON report")
    p.add_argument("--hist", metavar="PNG", help="write the min-angle histogram (before / after refinement)")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")


def write_histogram(result, path: str | Path, *, force: bool = False) -> None:
    """The paper's Fig. 5: the distribution of per-triangle minimum angles (matplotlib, Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from ..metrics import angle_histogram

    path = Path(path)
    if path.exists() and not force:
        raise OutputExistsError(f"{path}: exists already (use --force to overwrite)")
    edges, after = angle_histogram(result.min_angle_after)
    _, before = angle_histogram(result.min_angle_before)
    s = result.stats_after
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=100)
    w = np.diff(edges)
    ax.bar(edges[:-1], before / max(before.sum(), 1), width=w, align="edge", alpha=0.35, label="before (Stage II)")
    ax.bar(edges[:-1], after / max(after.sum(), 1), width=w, align="edge", alpha=0.75, label="after (Stage III)")
    ax.axvline(result.params.min_angle, color="k", lw=0.8, ls="--")
    ax.set_xlabel("minimum triangle angle, degrees")
    ax.set_ylabel("share of triangles")
    ax.set_title(f"{result.model.name}: {s.count} triangles, min {s.min:.1f}°, 1% {s.p01:.1f}°, "
                 f"median {s.median:.1f}°, <20° {100 * s.below_20:.1f}%, <30° {100 * s.below_30:.1f}%", fontsize=8)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, format="png")
    plt.close(fig)


def run(args: argparse.Namespace) -> int:
    out = check_output(args.output, force=args.force)
    for extra in (args.report, args.hist):
        if extra and Path(extra).exists() and not args.force:
            raise OutputExistsError(f"{extra}: exists already (use --force to overwrite)")
    spec = load_spec(input_path(args))
    params = spec.params(min_angle=args.min_angle, max_edge=args.max_edge, chord_arc=args.chord_arc,
                         max_triangles=args.max_triangles, cells=args.cells, max_deviation=args.max_deviation,
                         border_deviation=args.border_deviation, coarsen_angle=args.coarsen_angle,
                         seed=False if args.no_seed else None)
    result = mesh_hybrid(spec.model, params)
    save_mesh(result.mesh, out, force=args.force)
    rep = result.report()
    if args.report:
        write_json(args.report, rep, force=args.force)
    if args.hist:
        write_histogram(result, args.hist, force=args.force)
    s, t = result.stats_after, result.topology
    print(f"{spec.model.name}: {len(result.faces)} triangles ({rep['counts']['triangles_initial']} after Stage II, "
          f"{result.seeded} vertices seeded, {2 * result.collapses} triangles removed by coarsening), "
          f"{len(result.mesh.vertices)} vertices in "
          f"{rep['timings']['total']:.2f} s")
    print(f"min angle {s.min:.2f}° (before {result.stats_before.min:.2f}°), 1st percentile {s.p01:.2f}°, "
          f"median {s.median:.2f}°, below 30°: {100 * s.below_30:.2f} %, trim-corner exceptions "
          f"{len(result.corner_triangles)}")
    print(f"border: max |F| {result.max_abs_F:.3g}, max distance {result.max_border_distance:.3g}; "
          f"topology: {t.components} component(s), {t.boundary_loops} boundary loop(s), genus {t.genus:g}")
    if rep["hit_max_triangles"]:
        print("warning: stopped at --max-triangles before every triangle was good")
    print(f"wrote {out}")
    return 0

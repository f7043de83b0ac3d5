"""`bridgefield frep SPEC -o OUT`: triangulate a functionally defined object (spec/frep.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..io import InputError, OutputExistsError, check_output, save_mesh
from .common import add_input, input_path, write_json

NAME = "frep"
HELP = "triangulate an F-rep object (JSON spec) into a uniform watertight mesh (.ply/.obj/.stl/.off/.ase)"
OUT_FORMATS = ("ply", "obj", "stl", "off", "ase")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_input(p, points=False, kind="frep")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="output mesh (.ply .obj .stl .off .ase)")
    p.add_argument("--qlev", type=int, default=6, help="quadtree depth: S_xy = 1/2^QLEV of the box (default 6)")
    p.add_argument("--blev", type=int, default=12, help="ray subdivision depth: S_z = 1/2^BLEV (default 12)")
    p.add_argument("--diagonal", choices=("AC", "shorter"), default="shorter",
                   help="split quads ABCD along the shorter diagonal (default) or as ABC+ACD (the paper)")
    p.add_argument("--weight", choices=("area", "length"), default="area", help="Liepa weight for hole filling")
    p.add_argument("--no-merge", action="store_true", help="do not merge patches with zero-projected-area side faces")
    p.add_argument("--side-slope", type=float, default=0.6,
                   help="merge faces with |n_z| <= this into the refined region (default 0.6; 0 = only the "
                        "paper's zero-projected-area side faces)")
    p.add_argument("--no-refine", action="store_true", help="fill holes without refinement (and fairing)")
    p.add_argument("--fairing", choices=("U2", "U1", "none"), default="U2", help="fairing of the new vertices")
    p.add_argument("--no-project", action="store_true",
                   help="leave the new vertices where fairing puts them (default: moved onto F = 0)")
    p.add_argument("--smooth", type=int, default=None, metavar="K",
                   help="K rounds of isotropic improvement: valence edge flips and tangential CVT relaxation "
                        "of all vertices, each projected onto F = 0 (evens out edge lengths and angles; moves the "
                        "sample points off their rays; default: FrepParams.smooth = 10; 0 = the paper's pipeline)")
    p.add_argument("--report", metavar="R.json", help="write the JSON report (stages, metrics, timings)")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")


def run(args: argparse.Namespace) -> int:
    from ..frep.ase import save_ase
    from ..frep.objects import load_spec
    from ..frep.pipeline import FrepParams, triangulate_object

    out = Path(args.output)
    check_output(out, force=args.force, formats=OUT_FORMATS)
    if args.report:
        rp = Path(args.report)
        if rp.exists() and not args.force:
            raise OutputExistsError(f"{rp}: exists already (use --force to overwrite)")
        if rp.resolve() == out.resolve():
            raise InputError("the report and the mesh must be different files")
    params = FrepParams(qlev=args.qlev, blev=args.blev, diagonal=args.diagonal, weight=args.weight,
                        merge_sides=not args.no_merge, refine=not args.no_refine,
                        fairing="none" if args.no_refine else args.fairing,
                        side_slope=max(args.side_slope, 1e-6), project=not args.no_project,
                        **({} if args.smooth is None else {"smooth": args.smooth}))
    obj = load_spec(input_path(args))
    result = triangulate_object(obj, params)
    if not len(result.mesh.faces):
        raise InputError(f"{obj.name}: no surface found in the box {list(obj.bounds)} (F < 0 everywhere sampled)")
    if out.suffix.lower() == ".ase":
        save_ase(result.mesh, out, force=args.force, name=obj.name)
    else:
        save_mesh(result.mesh, out, force=args.force)
    m = result.metrics
    print(f"{obj.name}: {m.vertices} vertices, {m.faces} faces, holes filled {len(result.loops)}, "
          f"watertight {m.topology.watertight}, genus {m.topology.genus:g}; min angle < 20 deg "
          f"{100 * m.angles.below_20:.2f} %, edge CV {m.edge_cv:.3f}, face-normal error {m.face_normal_mean:.2f} deg; "
          f"{result.timings['total']:.2f} s -> {out}")
    if args.report:
        write_json(args.report, {"input": str(input_path(args)), "output": str(out), **result.report()},
                   force=args.force)
    return 0

"""`bridgefield repair IN -o OUT`: repair an incomplete mesh into a closed surface."""

from __future__ import annotations

import argparse
import dataclasses
import sys

from ..io import check_output, save_mesh
from ..params import MODES, TRACERS, FieldParams
from ..repair import DARNING, TUNNELS, RepairParams, repair
from .common import add_input, load_input_model, write_json

NAME = "repair"
HELP = "repair an incomplete mesh: connect islands, rebuild lost handles, split complex holes, darn"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_input(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="repaired mesh (.ply .obj .stl .off)")
    p.add_argument("--mode", choices=MODES, default="light", help="light (M1) or full (M2: shielding + free points)")
    p.add_argument("--ki", type=float, default=FieldParams.ki, help="factor of interpolation k_i (>= 0)")
    p.add_argument("--kt", type=float, default=FieldParams.kt, help="free-point trust k_t in (0, 1)")
    p.add_argument("--lc", type=float, default=None, help="characteristic length L_c (default: automatic)")
    p.add_argument("--tracer", choices=TRACERS, default=FieldParams.tracer)
    p.add_argument("--tunnels", choices=TUNNELS, default="auto", help="rebuild lost handles (default auto)")
    p.add_argument("--darning", choices=DARNING, default="liepa-fair", help="darning method (default liepa-fair)")
    p.add_argument("--report", metavar="R.json", help="write a JSON report")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")


def run(args: argparse.Namespace) -> int:
    out = check_output(args.output, force=args.force)
    if args.report:
        check_output(args.report, force=args.force, formats=("json",))
    fp = FieldParams(mode=args.mode, ki=args.ki, kt=args.kt, lc=args.lc, tracer=args.tracer)
    params = RepairParams(field=fp, tunnels=args.tunnels, darning=args.darning)
    model = load_input_model(args)

    def progress(frac: float, msg: str) -> None:
        if not args.quiet:
            print(f"\r[{frac * 100:3.0f}%] {msg:<60}", end="", file=sys.stderr, flush=True)

    result = repair(model, params, progress=progress)
    if not args.quiet:
        print(file=sys.stderr)
    save_mesh(result.mesh, out, force=args.force)
    rep = result.report()
    rep["input"] = str(model.source)
    rep["output"]["file"] = str(out)
    if args.report:
        write_json(args.report, rep, force=args.force)
    o = rep["output"]
    print(f"{out}: {o['faces']} faces ({rep['new_faces']} new), class {rep['class']}, "
          f"{rep['bridges']['count']} bridges, watertight {o['watertight']}, components {o['components']}, "
          f"genus {o['genus']:g}, {rep['timings']['total']:.2f} s")
    _ = dataclasses
    return 0

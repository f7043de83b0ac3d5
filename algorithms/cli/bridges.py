"""`bridgefield bridges IN --report R.json`: candidate bridges between islands (no darning).

Omega at every boundary point, force lines from its local maxima, every line reported (arrived
or the reason it stopped) with its polyline; spec/repair.md §4-6 step 1 (before conflicts).
"""

from __future__ import annotations

import argparse

import numpy as np

from ..bridges import BridgeSet, find_candidate_bridges
from ..params import KERNELS, MODES, TRACERS, FieldParams
from .common import add_input, dumps, load_input_model, write_json

NAME = "bridges"
HELP = "candidate bridges between islands by force lines (attraction index, tracing), as a JSON report"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_input(p)
    d = FieldParams()
    p.add_argument("--mode", choices=MODES, default=d.mode, help="light (M1) or full (M2: shielding + free points)")
    p.add_argument("--ki", type=float, default=d.ki, help=f"factor of interpolation k_i >= 0 (default {d.ki})")
    p.add_argument("--kt", type=float, default=d.kt, help=f"free-point trust k_t in (0,1) (default {d.kt})")
    p.add_argument("--tracer", choices=TRACERS, default=d.tracer, help="simple (2004) or predictor-corrector (2010)")
    p.add_argument("--q1-kernel", choices=KERNELS, default=d.q1_kernel, help="shortness kernel (3)")
    p.add_argument("--lc", type=float, default=None, help="L_c (default: automatic, spec §6)")
    p.add_argument("--step", type=float, default=None, help="tracing step (default: step_factor * L_c)")
    p.add_argument("--max-steps", type=int, default=d.max_steps, help=f"maximum steps per line (default {d.max_steps})")
    p.add_argument("--report", metavar="R.json", help="write the JSON report here")
    p.add_argument("--force", action="store_true", help="overwrite the report if it exists")
    p.add_argument("--json", action="store_true", help="print the JSON report on stdout")
    p.add_argument("--show", type=int, default=20, metavar="N", help="lines listed in the text output (default 20)")


def report(bs: BridgeSet, model) -> dict:
    """The report: params, lc, timings, attraction per loop, and every traced line."""
    from ..boundary import summarize

    loops = summarize(model).loops
    vert_loop = {int(v): k for k, lp in enumerate(loops) for v in lp.vertices}
    bridges = []
    for c in bs.candidates:
        ln = c.line
        bridges.append({
            "from_island": ln.start_island, "from_vertex": ln.start_vertex, "from_loop": c.start_loop,
            "to_island": ln.end_island if ln.arrived else None, "to_vertex": ln.end_vertex if ln.arrived else None,
            "to_loop": vert_loop.get(ln.end_vertex) if ln.arrived else None,
            "status": ln.status, "length": ln.length, "quality": ln.quality, "steps": ln.steps,
            "factors": c.factors.as_dict() if c.factors is not None else None,
            "points": np.round(ln.points, 7),
        })
    return {
        "source": model.source,
        "params": bs.params.as_dict(),
        "lc": bs.lc,
        "timings": bs.timings,
        "attraction": [{"loop": k, "island": lp.island, "vertices": lp.vertices, "omega": w}
                       for k, (lp, w) in enumerate(zip(loops, bs.attraction))],
        "arrived": len(bs.arrived()),
        "bridges": bridges,
    }


def run(args: argparse.Namespace) -> int:
    params = FieldParams(mode=args.mode, ki=args.ki, kt=args.kt, tracer=args.tracer, q1_kernel=args.q1_kernel,
                         lc=args.lc, step=args.step, max_steps=args.max_steps)
    model = load_input_model(args)
    if args.report:
        from pathlib import Path

        if Path(args.report).exists() and not args.force:
            write_json(args.report, {}, force=False)  # raises the standard "exists" error before any work
    bs = find_candidate_bridges(model, params)
    d = report(bs, model)
    if args.report:
        write_json(args.report, d, force=args.force)
    if args.json:
        print(dumps(d))
        return 0
    print(f"{model.source}: {len(bs.candidates)} lines traced, {len(bs.arrived())} arrived "
          f"(mode {params.mode}, tracer {params.tracer}, L_c {bs.lc:.4g}, {bs.timings.get('total', 0):.2f} s)")
    for b in d["bridges"][:args.show]:
        end = (f"-> island {b['to_island']} vertex {b['to_vertex']}" if b["status"] == "arrived"
               else f"{b['status']}")
        print(f"  island {b['from_island']} vertex {b['from_vertex']} {end}: length {b['length']:.4g}, "
              f"quality {b['quality']:.4g}, {b['steps']} steps")
    if len(d["bridges"]) > args.show:
        print(f"  ... {len(d['bridges']) - args.show} more (--show N, --json or --report)")
    return 0

"""`bridgefield shot [FILE | --demo NAME] [--mode M] [--ki K] [--repair] -o PNG`: the explorer's
scene rendered off screen (no display needed).

The same layers as the explorer's 3D view (viewer.scene.SceneLayers): islands, boundary loops,
free points, the attraction index Ω with its scalar bar, and the candidate bridges computed by
``algorithms.bridges.find_candidate_bridges`` as tubes coloured by quality with the labelled
scalar bar (lines that did not arrive by how they ended). With ``--repair`` the repair pipeline
runs too: only the bridges it kept are tubes, and its patches are drawn.
"""

from __future__ import annotations

import argparse

from algorithms.cli.common import add_input, load_input_model
from algorithms.io import check_output
from algorithms.params import MODES, FieldParams

NAME = "shot"
HELP = "render what the explorer shows (input, Ω, bridges by quality) to a PNG, off screen"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_input(p)
    d = FieldParams()
    p.add_argument("-o", "--output", required=True, metavar="PNG", help="image to write")
    p.add_argument("--mode", choices=MODES, default=d.mode, help="light (M1) or full (M2: shielding + free points)")
    p.add_argument("--ki", type=float, default=d.ki, help=f"factor of interpolation k_i >= 0 (default {d.ki})")
    p.add_argument("--repair", action="store_true", help="run the repair too: kept bridges and the patches")
    p.add_argument("--no-bridges", action="store_true", help="draw the input only (no field computed)")
    p.add_argument("--size", default="1200x900", help="WIDTHxHEIGHT in pixels (default 1200x900)")
    p.add_argument("--force", action="store_true", help="overwrite an existing image")


def compute(model, params: FieldParams, *, repair: bool = False):
    """(BridgeSet, RepairResult or None) for the scene."""
    from algorithms.bridges import find_candidate_bridges

    result = find_candidate_bridges(model, params) if model.mesh.n_faces else None
    rep = None
    if repair:
        from algorithms.repair import RepairParams
        from algorithms.repair import repair as run_repair

        rep = run_repair(model, RepairParams(field=params))
    return result, rep


def render(model, path: str, *, size: tuple[int, int] = (1200, 900), result=None, repair=None) -> None:
    """Draw the explorer's layers for a model (and a field result / repair) into a PNG."""
    import pyvista as pv

    from .scene import SceneLayers

    pl = pv.Plotter(off_screen=True, window_size=list(size))
    try:
        pl.set_background("white", top="#dfe7ee")
        layers = SceneLayers(pl)
        layers.draw_model(model)
        layers.draw_result(result, repair=repair)
        layers.draw_repair(repair)
        if result is not None and len(result.candidates):
            best = max(range(len(result.candidates)), key=lambda i: (result.candidates[i].line.arrived,
                                                                      result.candidates[i].quality))
            layers.draw_selection(result, best)
        layers.frame_camera()
        pl.screenshot(path)
    finally:
        pl.close()


def run(args: argparse.Namespace) -> int:
    out = check_output(args.output, force=args.force, formats=("png",))
    try:
        w, h = (int(x) for x in args.size.lower().split("x"))
    except ValueError:
        raise ValueError(f"--size must be WIDTHxHEIGHT, not {args.size!r}") from None
    model = load_input_model(args)
    params = FieldParams(mode=args.mode, ki=args.ki)
    result, rep = (None, None) if args.no_bridges else compute(model, params, repair=args.repair)
    render(model, str(out), size=(w, h), result=result, repair=rep)
    what = "" if result is None else (f": {len(result.candidates)} force lines, "
                                      f"{sum(c.line.arrived for c in result.candidates)} arrived")
    if rep is not None:
        what += f"; repaired with {len(rep.bridges)} bridges, {len(rep.new_faces)} new faces"
    print(f"wrote {out}{what}")
    return 0

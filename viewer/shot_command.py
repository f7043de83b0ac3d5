"""`bridgefield shot [FILE | --demo NAME] -o PNG`: the explorer's scene rendered off screen."""

from __future__ import annotations

import argparse

from algorithms.cli.common import add_input, load_input_model
from algorithms.io import check_output

NAME = "shot"
HELP = "render what the explorer shows to a PNG, off screen (no display needed)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_input(p)
    p.add_argument("-o", "--output", required=True, metavar="PNG", help="image to write")
    p.add_argument("--size", default="1200x900", help="WIDTHxHEIGHT in pixels (default 1200x900)")
    p.add_argument("--force", action="store_true", help="overwrite an existing image")


def render(model, path: str, *, size: tuple[int, int] = (1200, 900)) -> None:
    import pyvista as pv

    from .scene import draw_model, frame_camera

    pl = pv.Plotter(off_screen=True, window_size=list(size))
    pl.set_background("white", top="#dfe7ee")
    draw_model(pl, model)
    frame_camera(pl, model)
    pl.screenshot(path)
    pl.close()


def run(args: argparse.Namespace) -> int:
    out = check_output(args.output, force=args.force, formats=("png",))
    try:
        w, h = (int(x) for x in args.size.lower().split("x"))
    except ValueError:
        raise ValueError(f"--size must be WIDTHxHEIGHT, not {args.size!r}") from None
    model = load_input_model(args)
    render(model, str(out), size=(w, h))
    print(f"wrote {out}")
    return 0

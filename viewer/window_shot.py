"""A screenshot of the whole explorer window (the README's docs/screenshot.png).

Run under a display (e.g. ``xvfb-run -s '-screen 0 1600x1000x24' python -m viewer.window_shot
-o docs/screenshot.png``): opens the window on a demo, waits for the field's bridges, selects the
best bridge and shows its force line half traced, then grabs the screen area of the window.
Never overwrites a file without --force.
"""

from __future__ import annotations

import argparse
import sys
import time


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m viewer.window_shot", description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", required=True, metavar="PNG")
    p.add_argument("--demo", default="two-caps")
    p.add_argument("--size", default="1600x1000", help="window WIDTHxHEIGHT")
    p.add_argument("--elevation", type=float, default=-25.0, help="camera elevation change (degrees)")
    p.add_argument("--force", action="store_true")
    args = p.parse_args(argv)

    from algorithms.io import check_output

    out = check_output(args.output, force=args.force, formats=("png",))
    from PySide6.QtCore import QSettings
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication(sys.argv[:1])
    from .main_window import MainWindow

    w = MainWindow(settings=QSettings(str(out) + ".ini", QSettings.IniFormat))
    width, height = (int(x) for x in args.size.lower().split("x"))
    w.resize(width, height)
    w.move(0, 0)
    w.show()

    def wait(cond, seconds: float) -> None:
        t0 = time.perf_counter()
        while not cond() and time.perf_counter() - t0 < seconds:
            app.processEvents()
            time.sleep(0.01)

    w.open_demo(args.demo)
    wait(lambda: w.model.result is not None, 120)
    if w.model.result is None:
        print("no field result: nothing to show", file=sys.stderr)
        return 1
    cam = w.scene.plotter.camera
    cam.Elevation(args.elevation)
    cam.OrthogonalizeViewUp()
    w.reset_camera()
    line = w.model.line
    if line is not None:
        w.model.set_frame(line.steps * 2 // 3)
    wait(lambda: False, 1.5)  # every dock painted, the 3D view rendered
    geo = w.frameGeometry()
    img = app.primaryScreen().grabWindow(0, geo.x(), geo.y(), geo.width(), geo.height())
    img.save(str(out))
    w.close()
    print(f"wrote {out} ({img.width()}x{img.height()})")
    import os

    os.remove(str(out) + ".ini") if os.path.exists(str(out) + ".ini") else None
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Stand-ins for the field's results in viewer tests: real ForceLine records built from straight
segments between boundary loops, with qualities that depend on k_i (so an edit visibly changes
them). The viewer only reads records, so any records will do."""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from algorithms.boundary import loop_frames
from algorithms.records import ARRIVED, TOO_WEAK, BridgeFactors, Cancelled, ForceLine


def straight_line(a, b, steps: int, status: str = ARRIVED, start_vertex: int = 0, end_vertex: int = -1) -> ForceLine:
    t = np.linspace(0.0, 1.0, steps)[:, None]
    pts = (1 - t) * np.asarray(a, float) + t * np.asarray(b, float)
    d = np.asarray(b, float) - np.asarray(a, float)
    d /= np.linalg.norm(d) or 1.0
    normals = np.tile(np.cross(d, [0.0, 0.0, 1.0]) + [0, 0, 1e-9], (steps, 1))
    forces = np.tile(d, (steps, 1)) * np.linspace(1.0, 0.5, steps)[:, None]
    tensions = np.linalg.norm(forces, axis=1)
    return ForceLine(pts, normals, forces, tensions, status, start_vertex, 0,
                     end_vertex if status == ARRIVED else -1, 1 if status == ARRIVED else -1)


def fake_bridges(model, params, *, progress=None, cancel=None, delay: float = 0.0, n: int = 6):
    """A BridgeSet-shaped result: n lines from loop 0 to the nearest points of the last loop."""
    frames = loop_frames(model.mesh)
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < delay:  # a slow computation that checks for cancel
        if cancel is not None and cancel():
            raise Cancelled()
        time.sleep(0.005)
    a, b = frames[0], frames[-1]
    idx = np.linspace(0, len(a.points) - 1, n).astype(int)
    cands = []
    for k, i in enumerate(idx):
        dist = np.linalg.norm(b.points - a.points[i], axis=1)
        j = int(np.argmax(dist) if a is b else np.argmin(dist))  # one loop: across the hole
        status = ARRIVED if k < n - 1 else TOO_WEAK
        line = straight_line(a.points[i], b.points[j], 40, status, int(a.vertices[i]), int(b.vertices[j]))
        q = (k + 1) / n * (1.0 + params.ki * (k % 3)) / (1.0 + 0.5 * params.ki)
        f = BridgeFactors(1.0, 0.9, 0.0, 0.9, 0.8, 0.5 + 0.1 * k, q)
        cands.append(SimpleNamespace(line=line, factors=f, start_loop=0, start_index=int(i), quality=q))
        if progress is not None:
            progress((k + 1) / n)
    att = tuple(np.abs(np.sin(np.arange(len(f.points)) / 5.0)) * (1 + params.ki) for f in frames)
    return SimpleNamespace(params=params, lc=0.3, attraction=att, candidates=tuple(cands), timings={},
                           arrived=lambda: tuple(c for c in cands if c.line.arrived))


def fake_trace(model, params, vertex):
    frames = loop_frames(model.mesh)
    p = model.mesh.vertices[vertex]
    b = frames[-1].points
    dist = np.linalg.norm(b - p, axis=1)
    j = int(np.argmax(dist) if len(frames) == 1 else np.argmin(dist))
    return straight_line(p, b[j], 60, ARRIVED, int(vertex), int(frames[-1].vertices[j]))


def slow_count(n: int, pause: float, *, progress=None, cancel=None) -> int:
    """A long call for the worker processes: counts to n, pausing, checking cancel, reporting."""
    for k in range(n):
        if cancel is not None and cancel():
            raise Cancelled()
        if progress is not None:
            progress(k + 1, n)
        time.sleep(pause)
    return n


def busy_python(seconds: float) -> int:
    """Pure-Python work that holds the GIL in its process for `seconds`."""
    t0 = time.perf_counter()
    k = 0
    while time.perf_counter() - t0 < seconds:
        k += 1
    return k


def explorer_window(qtbot, tmp_path, **kw):
    """The explorer's main window with its own settings file, shown and exposed; yields it, then
    closes it and checks that no worker thread is left running (use as ``yield from``)."""
    from PySide6.QtCore import QSettings

    from viewer.main_window import MainWindow

    w = MainWindow(settings=QSettings(str(tmp_path / "settings.ini"), QSettings.IniFormat), **kw)
    qtbot.addWidget(w)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.close()
    assert w.worker.running() == 0

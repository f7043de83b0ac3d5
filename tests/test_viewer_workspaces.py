"""The explorer workspaces, driven like a user would (pytest-qt under Xvfb via pytest-xvfb)."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt

pytest.importorskip("pytestqt")

import re  # noqa: E402

from algorithms.demos import demo  # noqa: E402
from algorithms.frep.pipeline import FrepParams  # noqa: E402
from viewer.workspaces import FrepWorkspace, HybridWorkspace, open_workspace  # noqa: E402

pytestmark = pytest.mark.gui


def _close(qtbot, w) -> None:
    w.close()
    assert w.runner._pool.activeThreadCount() == 0  # no worker survives the widget


def _not_blank(img: np.ndarray) -> float:
    """Share of pixels that differ from the background gradient (per row: the row's median)."""
    rgb = np.asarray(img[..., :3], dtype=np.int32)
    bg = np.median(rgb, axis=1, keepdims=True)
    return float((np.abs(rgb - bg).sum(axis=2) > 40).mean())


def test_hybrid_threshold_moves_the_histogram(qtbot):
    w = HybridWorkspace(demo=None)
    qtbot.addWidget(w)
    w.show()
    qtbot.waitExposed(w)
    w.open_demo("bezier-hole")
    qtbot.waitUntil(lambda: w.current is not None, timeout=30_000)
    assert w.error is None
    first = w.current
    assert first.params.min_angle == 30.0
    counts30 = w.histogram.counts.copy()
    assert counts30.sum() == len(first.result.faces)
    # the guarantee: nothing below the threshold except reported trim-corner triangles
    keep = np.ones(len(first.result.faces), bool)
    keep[first.result.corner_triangles] = False
    assert first.result.min_angle_after[keep].min() >= 30.0 - 1e-6
    assert counts30[: int(30 / 2.5)].sum() == (~keep).sum()
    shown_min = first.result.min_angle_after[keep].min()
    assert f"min {shown_min:.2f}°" in w.stats_label.text()  # the label shows the computed bound
    # before refinement overlaid: the Stage II triangles
    assert w.histogram.overlay_counts is not None
    assert w.histogram.overlay_counts.sum() == len(first.result.initial_faces)

    # the user drags the threshold slider down to 20 degrees
    w.threshold_slider.setValue(20)
    assert w.threshold_spin.value() == 20.0
    assert w.busy  # debounced recompute under way (busy indicator shown)
    qtbot.waitUntil(lambda: w.current is not first and not w.busy, timeout=30_000)
    assert w.current.params.min_angle == 20.0
    counts20 = w.histogram.counts
    assert counts20.sum() == len(w.current.result.faces)
    assert not np.array_equal(counts20, counts30)  # the histogram changed
    assert counts20[: int(30 / 2.5)].sum() > 0  # triangles between 20 and 30 degrees are now allowed
    assert "threshold 20°" in w.stats_label.text()

    # switch the 3D view (and the histogram's bars) to before refinement, and the (u, v) view follows
    w.stage_combo.setCurrentIndex(w.stage_combo.findData("before"))
    assert w.histogram.counts.sum() == len(w.current.result.initial_faces)
    assert "Stage II" in w.uv_canvas.ax.get_title()
    img = w.plotter.screenshot(return_img=True)
    assert _not_blank(img) > 0.05

    # a tighter chordal tolerance (the curvature criterion) refines further
    coarse = w.current
    w.deviation_spin.setValue(0.0005)
    qtbot.waitUntil(lambda: w.current is not coarse and not w.busy, timeout=60_000)
    assert w.current.params.max_deviation == 0.0005
    assert len(w.current.result.faces) > len(coarse.result.faces)

    # the user types 0 in the coarsen-angle box: coarsening off, the refined mesh as it is (more triangles)
    coarsened = w.current
    assert coarsened.params.coarsen_angle == 36.0 and coarsened.result.collapses > 0
    edit = w.coarsen_spin.lineEdit()
    edit.selectAll()
    qtbot.keyClicks(edit, "0")
    qtbot.keyClick(edit, Qt.Key_Return)
    qtbot.waitUntil(lambda: w.current is not coarsened and not w.busy, timeout=60_000)
    assert w.coarsen_spin.text() == "off"
    assert w.current.params.coarsen_angle == 0.0 and w.current.result.collapses == 0
    assert len(w.current.result.faces) > len(coarsened.result.faces)
    _close(qtbot, w)


def test_hybrid_stale_results_dropped_and_bad_spec_reported(qtbot, tmp_path):
    w = HybridWorkspace(demo=None)
    qtbot.addWidget(w)
    bad = tmp_path / "bad.json"
    bad.write_text('{"surface": {"type": "nonsense"}}')
    w.open_spec(bad)
    assert w.error and "nonsense" in w.error and w.current is None
    w.open_demo("bezier-hole")
    w.cells_spin.setValue(12)  # edits while the first job runs: the first result is stale
    w.recompute()
    qtbot.waitUntil(lambda: w.current is not None and not w.busy, timeout=40_000)
    assert w.current.params.cells == 12
    assert w.runner.dropped >= 1
    # Cancel: the busy indicator goes at once and the running job's result is dropped on return
    kept, dropped = w.current, w.runner.dropped
    w.chord_spin.setValue(0.95)
    w.recompute()
    assert not w.progress.isHidden() and w.cancel_btn.isEnabled()
    qtbot.mouseClick(w.cancel_btn, Qt.MouseButton.LeftButton)
    assert not w.busy and w.progress.isHidden() and not w.cancel_btn.isEnabled()
    qtbot.waitUntil(lambda: w.runner.dropped > dropped, timeout=30_000)
    assert w.current is kept
    _close(qtbot, w)


def test_job_runner_latest_request_wins(qtbot):
    import threading

    from viewer.workspaces.common import JobRunner

    gate = threading.Event()

    def job(x):
        gate.wait(5)
        if x == "boom":
            raise ValueError("bad input")
        return x

    r = JobRunner()
    got, errors = [], []
    r.finished.connect(got.append)
    r.failed.connect(errors.append)
    for x in (1, 2, 3):  # 1 runs; 2 is replaced by 3 before it starts
        r.submit(job, x)
    assert r.busy
    gate.set()
    qtbot.waitUntil(lambda: not r.busy, timeout=5_000)
    assert got == [3] and r.dropped == 1
    r.submit(job, "boom")
    qtbot.waitUntil(lambda: bool(errors), timeout=5_000)
    assert errors == ["ValueError: bad input"] and got == [3]
    r.shutdown()


def test_frep_stages_on_the_timeline_with_metrics_and_pixels(qtbot):
    w = FrepWorkspace(demo=None)
    qtbot.addWidget(w)
    w.show()
    qtbot.waitExposed(w)
    w.qlev_spin.setValue(4)
    w.blev_spin.setValue(10)
    w.open_demo("sphere")
    qtbot.waitUntil(lambda: w.current is not None and not w.busy, timeout=30_000)
    assert w.error is None
    run = w.current
    names = [s.name for s in run.stages]
    assert names == ["points", "quads", "holes", "filled", "region", "refined", "faired"]
    assert w.stage_slider.maximum() == len(names) - 1 and w.stage_index() == len(names) - 1
    m = run.result.metrics
    assert m.topology.watertight
    # the metrics dock shows the numbers of the run
    text = w.metrics_label.text()
    assert f"{m.vertices} / {m.faces}" in text
    cv = re.search(r"edge-length CV</td><td align='right'>([0-9.]+)", text)
    assert cv and abs(float(cv.group(1)) - m.edge_cv) < 1e-2 and 0 < m.edge_cv < 1
    assert re.search(r"vertex mean / p95 / max</td><td align='right'>[0-9.]+", text)
    final = w.plotter.screenshot(return_img=True)
    assert _not_blank(final) > 0.05  # a real render: the sphere covers part of the view
    assert w.histogram.counts.sum() == m.faces

    # the timeline: first, next, next shows the holes with their loops highlighted
    qtbot.mouseClick(w.first_btn, Qt.MouseButton.LeftButton)
    assert w.stage_index() == 0 and "points" in w.stage_label.text()
    assert "loops" not in w.plotter.actors
    pts = w.plotter.screenshot(return_img=True)
    assert _not_blank(pts) > 0.01
    assert np.abs(pts.astype(int) - final.astype(int)).sum(axis=2).astype(bool).mean() > 0.01
    qtbot.mouseClick(w.next_btn, Qt.MouseButton.LeftButton)
    assert w.stage_index() == 1 and "quads" in w.stage_label.text()
    qtbot.mouseClick(w.next_btn, Qt.MouseButton.LeftButton)
    assert w.stage_index() == 2 and "hole loops" in w.stage_label.text()
    assert len(run.result.loops) > 0 and "loops" in w.plotter.actors
    assert w.histogram.counts.sum() == len(run.stages[2].faces)
    # play runs to the end and stops
    w.play_timer.setInterval(30)
    qtbot.mouseClick(w.play_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not w.play_btn.isChecked(), timeout=5_000)
    assert w.stage_index() == len(names) - 1 and "loops" not in w.plotter.actors

    # QLEV up: recomputed, a finer mesh
    w.qlev_spin.setValue(5)
    qtbot.waitUntil(lambda: w.current is not run and not w.busy, timeout=30_000)
    assert w.current.params.qlev == 5
    assert w.current.result.metrics.faces > m.faces
    # "Even out" 0 = the paper's pipeline: same vertices, less even edges than the default
    evened = w.current
    assert evened.params.smooth == FrepParams.smooth > 0
    w.smooth_spin.setValue(0)
    qtbot.waitUntil(lambda: w.current is not evened and not w.busy, timeout=30_000)
    assert w.current.params.smooth == 0
    assert w.current.result.metrics.vertices == evened.result.metrics.vertices
    assert w.current.result.metrics.edge_cv > evened.result.metrics.edge_cv
    _close(qtbot, w)


def test_open_workspace_as_a_window_on_a_spec(qtbot):
    w = open_workspace("frep", spec=str(demo("torus", "frep").path))
    qtbot.addWidget(w)
    assert w.isWindow() and w.isVisible()
    w.qlev_spin.setValue(4)  # a user lowers QLEV: the debounced recompute replaces the first run
    qtbot.waitUntil(lambda: w.current is not None and w.current.params.qlev == 4 and not w.busy, timeout=30_000)
    assert w.current.name == "torus"
    assert w.current.result.metrics.topology.genus == 1
    _close(qtbot, w)

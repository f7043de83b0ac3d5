"""The explorer workspaces, driven like a user would (pytest-qt under Xvfb via pytest-xvfb)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pytestqt")

from viewer.workspaces import HybridWorkspace  # noqa: E402

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
    assert "min 30." in w.stats_label.text()
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
    _close(qtbot, w)

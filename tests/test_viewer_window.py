"""The explorer window, driven like a user (pytest-qt under Xvfb).

The field's results come from tests/viewer_fakes.py here (real ForceLine records, qualities that
depend on k_i): these tests check the window, not the field. tests/test_viewer_field.py runs
the window on the real field.
"""

from __future__ import annotations

import time
from functools import partial

import numpy as np
import pytest

pytest.importorskip("pytestqt")
from PySide6.QtCore import QSettings, Qt  # noqa: E402
from viewer_fakes import explorer_window, fake_bridges, fake_trace  # noqa: E402

from viewer.main_window import MainWindow  # noqa: E402
from viewer.scene import QUALITY_BAR  # noqa: E402


@pytest.fixture
def win(qtbot, tmp_path):
    yield from explorer_window(qtbot, tmp_path, find=fake_bridges, trace=fake_trace)


def open_demo(qtbot, w, name="two-caps"):
    w.open_demo(name)
    qtbot.waitUntil(lambda: w.model.result is not None, timeout=10000)


def bar_colour_present(img, cmap="viridis", tol=18) -> int:
    """How many pixels look like the middle of the colour map (not the pastel islands)."""
    import matplotlib

    c = np.array(matplotlib.colormaps[cmap](np.linspace(0.1, 0.9, 9))[:, :3] * 255)
    px = img[..., :3].reshape(-1, 3).astype(float)
    d = np.min(np.linalg.norm(px[:, None, :] - c[None], axis=2), axis=1)
    return int((d < tol).sum())


def drawn_bridge_colours(w) -> np.ndarray:
    """The colours the bridges' lookup table gives their tube points, one per kept bridge."""
    from viewer.scene import kept_mask, qualities

    lut = w.scene.layers.actor("bridges").mapper.lookup_table
    q = qualities(w.model.result)[kept_mask(w.model.result)]
    return np.array([lut.map_value(float(v))[:3] for v in q], dtype=float)


def test_first_frame_within_3_s(qtbot, tmp_path):
    t0 = time.perf_counter()
    w = MainWindow(settings=QSettings(str(tmp_path / "s.ini"), QSettings.IniFormat), find=fake_bridges)
    qtbot.addWidget(w)
    w.show()
    qtbot.waitExposed(w)
    img = w.scene.grab()
    dt = time.perf_counter() - t0
    print(f"first frame {dt * 1000:.0f} ms")
    assert img.shape[0] > 100 and dt < 3.0
    w.close()


def test_open_demo_draws_layers_and_bridges(qtbot, win):
    open_demo(qtbot, win)
    actors = win.scene.layers._renderer().actors
    for name in ("islands", "loops", "free_points", "attraction", "bridges", "rejected", "line"):
        assert name in actors, name
    assert win.bridges.table_model.rowCount() == 6
    assert "two-caps" in win.windowTitle()
    assert win.recent_files() and win.recent_files()[0].endswith("two-caps.ply")
    # the render is not blank and shows the bridge colour map
    img = win.scene.grab()
    assert img.std() > 10
    assert bar_colour_present(img) > 200


def test_ki_slider_recomputes_colours_and_undo(qtbot, win):
    open_demo(qtbot, win)
    m = win.model
    before_q = [c.quality for c in m.result.candidates]
    before_rgb = drawn_bridge_colours(win)
    slider = win.parameters.ki_slider
    slider.setFocus()
    t0 = time.perf_counter()
    qtbot.keyClick(slider, Qt.Key_PageDown)  # a user nudging the slider: k_i 1.0 -> 0.75
    assert m.params.ki == pytest.approx(0.75)
    assert win.parameters.ki_spin.value() == pytest.approx(0.75)
    qtbot.waitUntil(lambda: m.result.params.ki == pytest.approx(0.75), timeout=5000)
    dt = time.perf_counter() - t0
    print(f"k_i edit -> new colours drawn: {dt * 1000:.0f} ms")
    assert dt < 1.5  # target 0.5 s; generous here because CI machines are shared
    after_q = [c.quality for c in m.result.candidates]
    assert after_q != before_q
    after_rgb = drawn_bridge_colours(win)
    assert after_rgb.shape == before_rgb.shape and np.abs(after_rgb - before_rgb).max() > 0.05
    # undo restores k_i (and recomputes): the shortcut, typed with the slider focused
    win.activateWindow()
    qtbot.waitUntil(win.isActiveWindow, timeout=2000)
    qtbot.keyClick(slider, Qt.Key_Z, Qt.ControlModifier)
    assert m.params.ki == pytest.approx(1.0)
    assert slider.value() == 100
    qtbot.waitUntil(lambda: m.result.params.ki == pytest.approx(1.0), timeout=5000)
    qtbot.keyClick(slider, Qt.Key_Z, Qt.ControlModifier | Qt.ShiftModifier)
    assert m.params.ki == pytest.approx(0.75)


def test_play_advances_frames(qtbot, win):
    open_demo(qtbot, win)
    tl = win.timeline
    tl.first()
    assert win.model.frame == 0
    qtbot.mouseClick(tl.play_button, Qt.LeftButton)
    assert tl.playing
    qtbot.waitUntil(lambda: win.model.frame > 5, timeout=3000)
    assert tl.slider.value() == win.model.frame
    assert "step" in tl.label.text()
    qtbot.mouseClick(tl.play_button, Qt.LeftButton)
    assert not tl.playing
    k = win.model.frame
    qtbot.mouseClick(tl.forward_button, Qt.LeftButton)
    assert win.model.frame == k + 1
    qtbot.mouseClick(tl.back_button, Qt.LeftButton)
    assert win.model.frame == k
    qtbot.mouseClick(tl.last_button, Qt.LeftButton)
    assert win.model.frame == win.model.line.steps - 1


def test_animation_frame_rate(qtbot, win):
    """Frames of a 500-step line: the in-place update of a frame costs far less than 1/30 s.

    The render itself is printed, not asserted: under Xvfb the GL is software (llvmpipe) and its
    cost depends on the pixel count and on how busy the machine is (10-25 frames a second for a
    500x540 view on 2 busy cores; a GPU renders this scene in about a millisecond). Playback
    advances by elapsed time, so a slow renderer skips steps instead of slowing the animation.
    """
    from viewer_fakes import straight_line

    open_demo(qtbot, win)
    for d in (win.dock_bridges, win.dock_plot, win.dock_inspector):
        d.hide()
    win.resize(800, 560)
    qtbot.wait(200)
    line = straight_line([0, 0, 0], [0.5, 0.2, 0.1], 500)
    win.model.set_line(line, frame=0)
    win.scene.render_now()
    print("3D view size", win.scene.plotter.window_size)
    t0 = time.perf_counter()
    for k in range(500):
        win.model.set_frame(k)  # the line, head, arrows, inspector, plot marker and slider
    update_fps = 500 / (time.perf_counter() - t0)
    t0 = time.perf_counter()
    for k in range(0, 500, 10):
        win.model.set_frame(k)
        win.scene.render_now()
    fps = 50 / (time.perf_counter() - t0)
    print(f"frame updates {update_fps:.0f}/s; updates + renders {fps:.1f}/s")
    assert update_fps >= 120, update_fps
    # the line mesh is updated in place: one actor, as many points as the line
    assert win.scene.layers._line_mesh.n_points == 500


def test_click_boundary_point_traces_line(qtbot, win):
    open_demo(qtbot, win)
    f = win.model.frames[0]
    win.scene.on_pick(f.points[3] + 1e-4)  # the handler the VTK picker calls
    qtbot.waitUntil(lambda: win.model.line_label.startswith("traced"), timeout=5000)
    assert win.model.line.start_vertex == int(f.vertices[3])
    assert win.model.selection == -1
    assert "Boundary point" in win.inspector.html() and "tension" in win.inspector.html()
    assert win.timeline.playing


def test_pick_bridge_selects_row(qtbot, win):
    open_demo(qtbot, win)
    c = win.model.result.candidates[2]
    mid = c.line.points[len(c.line.points) // 2]
    win.scene.on_pick(mid)
    assert win.model.selection == 2
    rows = win.bridges.view.selectionModel().selectedRows()
    assert win.bridges.proxy.mapToSource(rows[0]).row() == 2
    assert "q4 (7)" in win.inspector.html()
    # and the table selects back
    win.bridges.view.selectRow(win.bridges.view_row(4))
    assert win.model.selection == 4


def test_session_roundtrip(qtbot, win, tmp_path):
    open_demo(qtbot, win)
    win.model.edit(ki=0.3, mode="full")
    win.scene.plotter.camera.azimuth = 0
    win.scene.plotter.camera.Azimuth(40)
    cam = win.scene.camera_state()
    path = tmp_path / "s.json"
    win.save_session_file(str(path))
    win.model.edit(ki=2.0, mode="light")
    win.reset_camera()
    win.open_demo("big-hole")
    qtbot.waitUntil(lambda: win.model.source.demo == "big-hole", timeout=5000)
    win.load_session_file(str(path))
    qtbot.waitUntil(lambda: win.model.source.demo == "two-caps", timeout=5000)
    assert win.model.params.ki == pytest.approx(0.3) and win.model.params.mode == "full"
    assert np.allclose(win.scene.camera_state()["position"], cam["position"])
    assert np.allclose(win.scene.camera_state()["focal_point"], cam["focal_point"])


def test_cancel_stops_worker_and_gui_stays_responsive(qtbot, tmp_path):
    settings = QSettings(str(tmp_path / "s.ini"), QSettings.IniFormat)
    w = MainWindow(settings=settings, find=partial(fake_bridges, delay=1.5), trace=fake_trace)
    qtbot.addWidget(w)
    w.show()
    qtbot.waitExposed(w)
    w.open_demo("two-caps")
    qtbot.waitUntil(lambda: w.model.icadm is not None, timeout=5000)
    qtbot.wait(300)  # the new input's first render (not part of the recompute)
    # heartbeat: the GUI thread is never blocked more than 100 ms while the worker runs
    beats = []
    from PySide6.QtCore import QTimer

    hb = QTimer()
    hb.timeout.connect(lambda: beats.append(time.perf_counter()))
    hb.start(10)
    assert w.worker.busy
    qtbot.wait(500)
    hb.stop()
    assert w.cancel_button.isEnabled()
    t0 = time.perf_counter()
    qtbot.mouseClick(w.cancel_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.worker.running() == 0, timeout=2000)
    assert time.perf_counter() - t0 < 0.5
    assert w.model.result is None  # the cancelled job's result never lands
    gaps = np.diff(beats)
    print(f"heartbeat: {len(beats)} beats, longest gap {gaps.max() * 1000:.0f} ms")
    assert len(gaps) > 20 and gaps.max() < 0.1, gaps.max()
    w.close()
    assert w.worker.running() == 0


def test_stale_job_result_dropped(qtbot, tmp_path):
    settings = QSettings(str(tmp_path / "s.ini"), QSettings.IniFormat)
    w = MainWindow(settings=settings, find=partial(fake_bridges, delay=0.3), trace=fake_trace)
    qtbot.addWidget(w)
    w.show()
    w.open_demo("two-caps")
    qtbot.waitUntil(lambda: w.worker.busy and w.model.icadm is not None, timeout=5000)
    for ki in (0.1, 0.2, 0.3):
        w.model.edit(ki=ki)
        qtbot.wait(150)  # longer than the debounce: each starts a job, cancelling the last
    qtbot.waitUntil(lambda: w.model.result is not None and not w.worker.busy, timeout=5000)
    assert w.model.result.params.ki == pytest.approx(0.3)
    w.close()
    assert w.worker.running() == 0


def test_bad_file_shows_message_and_window_keeps_working(qtbot, win, tmp_path):
    bad = tmp_path / "bad.ply"
    bad.write_text("this is not a ply file")
    win.open_path(str(bad))
    qtbot.waitUntil(lambda: bool(win.errors), timeout=5000)
    assert "Cannot open" in win.errors[-1]
    assert win._error_box is not None and win._error_box.isVisible()
    open_demo(qtbot, win)  # still works
    assert win.model.source.demo == "two-caps"


def test_exports_and_compare(qtbot, win, tmp_path):
    import imageio.v2 as imageio

    open_demo(qtbot, win)
    png = tmp_path / "shot.png"
    win.save_screenshot(str(png))
    img = imageio.imread(png)
    assert img.std() > 10 and bar_colour_present(img) > 100
    gif = tmp_path / "anim.gif"
    n = win.export_animation(str(gif), max_frames=8)
    assert n >= 8 and len(imageio.mimread(gif)) >= 2  # identical frames (line behind the model) merge
    cw = win.open_compare()
    qtbot.waitUntil(lambda: all(r is not None for r in cw.results), timeout=5000)
    assert cw.results[0].params.ki == 0.0 or cw.results[0].params.mode == "light"
    cw.preset.setCurrentIndex(1)
    qtbot.waitUntil(lambda: all(r is not None for r in cw.results), timeout=5000)
    assert [r.params.ki for r in cw.results] == [0.0, 1.0]
    assert QUALITY_BAR + " " in cw.plotter.scalar_bars
    had_surface = getattr(cw.plotter, "_surface", None) is not None
    cw.close()
    if hasattr(cw.plotter, "_forget_context"):  # pyvistaqt >= 0.13 wraps the widget's GL surface
        # closing drops that wrapper of a C++-owned object (viewer/plotter_close.py)
        assert had_surface and cw.plotter._surface is None


def test_layer_toggle(qtbot, win):
    open_demo(qtbot, win)
    win.layer_actions["bridges"].trigger()
    assert not win.scene.layers.actor("bridges").GetVisibility()
    assert not win.parameters.layer_boxes["bridges"].isChecked()
    win.parameters.layer_boxes["bridges"].setChecked(True)
    assert win.scene.layers.actor("bridges").GetVisibility()

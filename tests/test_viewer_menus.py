"""Every menu item of the explorer, triggered like a user would (pytest-qt under Xvfb).

File dialogs are answered by the test (monkeypatched static dialogs); everything else is the
real window on the real field and repair.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("pytestqt")
from PySide6.QtWidgets import QApplication, QFileDialog, QMessageBox  # noqa: E402
from viewer_fakes import explorer_window  # noqa: E402

from viewer.workspaces import FrepWorkspace, HybridWorkspace  # noqa: E402

pytestmark = pytest.mark.gui


@pytest.fixture
def win(qtbot, tmp_path):
    yield from explorer_window(qtbot, tmp_path)


def menu_action(menu, prefix: str):
    for a in menu.actions():
        if a.text().replace("&", "").startswith(prefix):
            return a
    raise AssertionError(f"no menu item {prefix!r} in {[a.text() for a in menu.actions()]}")


def test_demos_menu_opens_the_workspaces(qtbot, win):
    hybrid = menu_action(win.demos_menu, "bezier-hole")
    frep = menu_action(win.demos_menu, "sphere")
    assert hybrid.isEnabled() and frep.isEnabled()
    hybrid.trigger()
    w = win.workspaces[-1]
    assert isinstance(w, HybridWorkspace) and w.isWindow() and w.isVisible()
    qtbot.waitUntil(lambda: w.current is not None and not w.busy, timeout=60_000)
    assert w.error is None and w.current.name == "bezier-hole"
    menu_action(win.demos_menu_file, "sphere").trigger()  # the File > Demos copy of the menu
    f = win.workspaces[-1]
    assert isinstance(f, FrepWorkspace) and f.isWindow() and f is not w
    qtbot.waitUntil(lambda: f.current is not None and not f.busy, timeout=60_000)
    assert f.error is None and f.current.name == "sphere"
    assert frep.text().endswith("(frep)")
    # closing the explorer closes its workspaces and stops their workers
    pools = [w.runner._pool, f.runner._pool]
    win.close()
    assert all(p.activeThreadCount() == 0 for p in pools)
    assert win.workspaces == []


def test_every_menu_item(qtbot, win, tmp_path, monkeypatch):
    """The walk a new user would make: every item of every menu does what it says."""
    from algorithms.demos import demo

    shown = []
    monkeypatch.setattr(QMessageBox, "show", lambda self: shown.append(self.windowTitle()))
    answers = {}
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (answers.pop("open"), ""))
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (answers.pop("save"), ""))
    menus = {m.title().replace("&", ""): m for m in (a.menu() for a in win.menuBar().actions())}
    assert list(menus) == ["File", "Edit", "View", "Playback", "Demos", "Help"]
    m = win.model

    # Demos > two-caps (repair): the explorer opens it
    menu_action(menus["Demos"], "two-caps").trigger()
    qtbot.waitUntil(lambda: m.result is not None, timeout=30_000)
    assert m.source.demo == "two-caps"
    # File > Open mesh…
    answers["open"] = str(demo("four-islands").path)
    menu_action(menus["File"], "Open mesh").trigger()
    qtbot.waitUntil(lambda: m.source.path.endswith("four-islands.ply") and m.result is not None, timeout=30_000)
    # File > Open point cloud…: free points added to the current mesh
    pts = tmp_path / "pts.xyz"
    np.savetxt(pts, m.icadm.mesh.vertices[:5] + 0.01)
    answers["open"] = str(pts)
    menu_action(menus["File"], "Open point cloud").trigger()
    qtbot.waitUntil(lambda: m.source.points is not None and len(m.icadm.free_points) == 5, timeout=30_000)
    # File > Open recent: the list has both files; the first entry reopens it
    recent = menu_action(menus["File"], "Open recent").menu()
    assert recent.actions()[0].text().endswith("four-islands.ply")
    recent.actions()[1].trigger()
    qtbot.waitUntil(lambda: m.source.path.endswith("two-caps.ply") and m.result is not None, timeout=30_000)
    # File > Save mesh (normalised input)…
    answers["save"] = str(tmp_path / "input.ply")
    menu_action(menus["File"], "Save mesh").trigger()
    assert (tmp_path / "input.ply").stat().st_size > 1000
    # Edit > Repair, then File > Save repaired mesh… (enabled only now)
    save_rep = menu_action(menus["File"], "Save repaired mesh")
    assert not save_rep.isEnabled()
    menu_action(menus["Edit"], "Repair").trigger()
    qtbot.waitUntil(lambda: m.repair is not None, timeout=30_000)
    assert save_rep.isEnabled()
    monkeypatch.setattr(QFileDialog, "exec", lambda self: (self.selectFile(str(tmp_path / "fixed.ply")), 1)[1])
    save_rep.trigger()
    assert (tmp_path / "fixed.ply").stat().st_size > 1000
    # File > Export screenshot / animation
    answers["save"] = str(tmp_path / "view.png")
    menu_action(menus["File"], "Export screenshot").trigger()
    assert (tmp_path / "view.png").stat().st_size > 1000
    m.set_timeline_mode("line")
    answers["save"] = str(tmp_path / "anim.gif")
    menu_action(menus["File"], "Export animation").trigger()
    assert (tmp_path / "anim.gif").stat().st_size > 1000
    # File > Save session / Load session
    answers["save"] = str(tmp_path / "s.json")
    menu_action(menus["File"], "Save session").trigger()
    saved = json.loads((tmp_path / "s.json").read_text())
    assert saved["input"]["demo"] == "two-caps" and saved["darning"] == "liepa-fair"
    m.edit(ki=0.25)
    answers["open"] = str(tmp_path / "s.json")
    menu_action(menus["File"], "Load session").trigger()
    assert m.params.ki == 1.0
    # Edit > Undo / Redo / Recompute / Cancel
    assert menu_action(menus["Edit"], "Undo").isEnabled()
    menu_action(menus["Edit"], "Undo").trigger()
    assert m.params.ki == 0.25
    menu_action(menus["Edit"], "Redo").trigger()
    assert m.params.ki == 1.0
    menu_action(menus["Edit"], "Recompute").trigger()
    assert win.worker.busy
    menu_action(menus["Edit"], "Cancel").trigger()
    qtbot.waitUntil(lambda: win.worker.running() == 0, timeout=10_000)
    # View > every layer toggles its actors; reset camera; docks hide and show
    for name, a in win.layer_actions.items():
        a.trigger()
        assert not win.scene.layers.visible[name] and not win.parameters.layer_boxes[name].isChecked()
        a.trigger()
        assert win.scene.layers.visible[name]
    v = m.icadm.mesh.vertices
    centre, size = (v.min(0) + v.max(0)) / 2, float(np.linalg.norm(v.max(0) - v.min(0)))
    win.scene.plotter.camera.focal_point = centre + size  # the user panned far away
    menu_action(menus["View"], "Reset camera").trigger()
    assert np.linalg.norm(np.array(win.scene.camera_state()["focal_point"]) - centre) < 0.1 * size
    dock = menu_action(menus["View"], "Plot")
    dock.trigger()
    assert not win.dock_plot.isVisible()
    dock.trigger()
    assert win.dock_plot.isVisible()
    # View > Compare side by side…
    menu_action(menus["View"], "Compare").trigger()
    cw = win.compare_window
    qtbot.waitUntil(lambda: all(r is not None for r in cw.results), timeout=30_000)
    cw.close()
    # Playback > every item
    m.select(0)
    pb = menus["Playback"]
    menu_action(pb, "First step").trigger()
    assert m.frame == 0
    menu_action(pb, "Step forward").trigger()
    assert m.frame == 1
    menu_action(pb, "Step back").trigger()
    assert m.frame == 0
    menu_action(pb, "Last step").trigger()
    assert m.frame == m.line.steps - 1
    menu_action(pb, "Loop").trigger()
    assert win.timeline.loop.isChecked()
    menu_action(pb, "Play").trigger()
    assert win.timeline.playing
    menu_action(pb, "Play").trigger()
    assert not win.timeline.playing
    stages = menu_action(pb, "Repair stages")
    assert not stages.isEnabled()  # the cancel above dropped the repair: nothing to play
    menu_action(menus["Edit"], "Repair").trigger()
    qtbot.waitUntil(lambda: m.repair is not None, timeout=30_000)
    assert stages.isChecked() and m.timeline_mode == "stages" and win.timeline.mode.currentIndex() == 1
    stages.trigger()
    assert m.timeline_mode == "line" and win.timeline.mode.currentIndex() == 0
    stages.trigger()
    assert m.timeline_mode == "stages"
    # Help
    menu_action(menus["Help"], "Shortcuts").trigger()
    menu_action(menus["Help"], "About").trigger()
    assert shown[-2:] == ["Shortcuts", "About Bridgefield"]
    assert not win.errors, win.errors
    # File > Quit
    menu_action(menus["File"], "Quit").trigger()
    qtbot.waitUntil(lambda: not win.isVisible(), timeout=5000)
    assert win.worker.running() == 0
    QApplication.processEvents()

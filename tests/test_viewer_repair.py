"""The explorer on the real field and the real repair pipeline (pytest-qt under Xvfb).

Driven like a user: open the two-caps demo, press Repair (F6), see kept and rejected bridges
told apart, the patches layer, the repair's stages on the timeline, a darning edit that
recomputes the repair, and the repaired mesh saved (never over an existing file without force).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pytestqt")
from PySide6.QtCore import Qt  # noqa: E402
from viewer_fakes import explorer_window  # noqa: E402

from algorithms.io import load_model  # noqa: E402
from algorithms.metrics import topology  # noqa: E402
from viewer.scene import bridge_verdicts  # noqa: E402
from viewer.stages import patch_faces_by_hole, stage_frames  # noqa: E402

pytestmark = pytest.mark.gui


@pytest.fixture
def win(qtbot, tmp_path):
    yield from explorer_window(qtbot, tmp_path)


def repaired(qtbot, w, name="two-caps"):
    w.open_demo(name)
    qtbot.waitUntil(lambda: w.model.result is not None, timeout=30000)
    assert not w.act_save_repaired.isEnabled()
    w.activateWindow()
    qtbot.waitUntil(w.isActiveWindow, timeout=2000)
    qtbot.keyClick(w, Qt.Key_F6)  # Edit > Repair
    qtbot.waitUntil(lambda: w.model.repair is not None, timeout=30000)


def test_repair_keeps_and_rejects_bridges_and_draws_patches(qtbot, win):
    repaired(qtbot, win)
    m = win.model
    r = m.repair
    assert topology(r.mesh.faces).watertight
    kept, why = bridge_verdicts(m.result, r)
    # the repair's island bridges are exactly the candidates drawn as kept (matched by end vertices)
    island = {(b.start, b.end) for b in r.bridges if b.kind == "island"}
    drawn = {(int(c.line.start_vertex), int(c.line.end_vertex)) for c, k in zip(m.result.candidates, kept) if k}
    assert drawn == island and 0 < kept.sum() < sum(c.line.arrived for c in m.result.candidates)
    assert any("neighbourhood" in w for w in why)  # a conflict reason from the repair
    # the drawn tubes: only the kept ones; the rejected layer holds the rest as lines
    layers = win.scene.layers
    assert layers.actor("bridges") is not None and layers.actor("rejected") is not None
    assert layers.meshes["rejected"].n_cells == len(m.result.candidates) - kept.sum()
    # the Bridges table says so
    tm = win.bridges.table_model
    col = tm.columnCount() - 1
    texts = {tm.data(tm.index(i, col)) for i in range(tm.rowCount())}
    assert "kept by the repair" in texts
    # the patches layer shows the new faces (mid-play of the stages, or all of them)
    win.timeline.pause()
    m.set_timeline_mode("line")
    patches = layers.actor("patches")
    assert patches is not None and patches.GetVisibility()
    assert layers.meshes["patches"].n_cells == len(r.new_faces)
    win.layer_actions["patches"].trigger()
    assert not patches.GetVisibility()
    assert win.act_save_repaired.isEnabled()
    assert "watertight" in win.status.text() or "Repaired" in win.status.text()


def test_repair_stages_on_the_timeline(qtbot, win):
    repaired(qtbot, win)
    m, tl = win.model, win.timeline
    assert m.timeline_mode == "stages"  # F6 shows the stages and plays them
    tl.pause()
    names = [s.name for s in m.stages]
    assert names[:4] == ["input", "bridges", "holes", "split"] and names[-1] == "darned"
    n_holes = sum(h.split_by < 0 for h in m.repair.holes)
    assert len(names) == 4 + n_holes  # the patches fill hole by hole
    assert tl.slider.maximum() == len(names) - 1
    tl.first()
    assert m.stage == 0 and "input" in tl.label.text()
    # field layers are hidden while the stages play; the stage's hole outlines are drawn
    layers = win.scene.layers
    assert not layers.actor("bridges").GetVisibility()
    assert layers.actor("holes") is not None and layers.actor("patches") is None
    qtbot.mouseClick(tl.forward_button, Qt.LeftButton)
    assert m.stage == 1 and layers.actor("chains") is not None  # bridges appear
    win.inspector.refresh()
    qtbot.wait(200)
    assert "stage 2 / " in win.inspector.html() and f"{len(m.repair.new_faces)} new faces" in win.inspector.html()
    tl.last()
    assert layers.meshes["patches"].n_cells == len(m.repair.new_faces)
    # the patch counts grow stage after stage
    counts = [0 if s.patches is None else len(s.patches) for s in m.stages]
    assert counts == sorted(counts) and counts[-1] == len(m.repair.new_faces)
    # play runs through the stages
    tl.first()
    tl.speed.setValue(600)  # 20 stages a second
    qtbot.mouseClick(tl.play_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: m.stage == len(names) - 1, timeout=5000)
    # back to the force line: the field layers come back
    tl.mode.setCurrentIndex(0)
    assert m.timeline_mode == "line" and layers.actor("bridges").GetVisibility()
    assert layers.actor("holes") is None
    assert not win.act_stages.isChecked()


def test_darning_edit_recomputes_the_repair_and_undo(qtbot, win):
    repaired(qtbot, win)
    m = win.model
    first = m.repair
    assert first.params.darning == "liepa-fair"
    win.parameters.darning.setCurrentText("fan")
    assert m.darning == "fan" and m.repair is None  # a stale repair is never shown
    qtbot.waitUntil(lambda: m.repair is not None, timeout=30000)
    assert m.repair.params.darning == "fan"
    assert m.repair.fairing == "none" and len(m.repair.new_faces) != len(first.new_faces)
    # a k_i edit recomputes both the field and the repair
    m.edit(ki=0.5)
    qtbot.waitUntil(lambda: m.repair is not None and m.result.params.ki == 0.5, timeout=30000)
    assert m.repair.params.field.ki == 0.5 and m.repair.params.darning == "fan"
    m.undo()
    assert m.params.ki == 1.0 and m.darning == "fan"
    m.undo()
    assert m.darning == "liepa-fair" and win.parameters.darning.currentText() == "liepa-fair"
    qtbot.waitUntil(lambda: m.repair is not None and m.repair.params.darning == "liepa-fair", timeout=30000)


def test_save_repaired_mesh(qtbot, win, tmp_path):
    repaired(qtbot, win)
    out = tmp_path / "fixed.ply"
    assert win.save_repaired(str(out))
    back = load_model(out)
    assert back.mesh.n_faces == win.model.repair.mesh.n_faces
    size = out.stat().st_size
    out.write_bytes(b"keep me")
    assert not win.save_repaired(str(out))  # exists: refused without force, file untouched
    assert out.read_bytes() == b"keep me" and "exists" in win.errors[-1]
    assert win.save_repaired(str(out), force=True) and out.stat().st_size == size


def test_stage_frames_cover_every_new_face_once():
    from algorithms.demos import demo
    from algorithms.repair import repair

    r = repair(load_model(demo("cut-torus").path))
    per_hole = patch_faces_by_hole(r)
    allf = np.vstack([p for p in per_hole if len(p)])
    darned = r.stages[-1]
    new = darned.faces[len(darned.faces) - len(r.new_faces):]
    assert len(allf) == len(new) and {tuple(f) for f in allf} == {tuple(f) for f in new}
    polys = [h.polygon for h in r.holes if h.split_by < 0]
    for p, f in zip(polys, per_hole):  # each patch touches its own hole
        assert len(f) and set(p) & set(f.ravel().tolist())
    frames = stage_frames(r)
    assert [len(f.patches) for f in frames if f.patches is not None][-1] == len(r.new_faces)


def test_repair_of_a_single_hole(qtbot, win):
    """One loop, no islands to join: no bridges, the hole is darned; the stages still play."""
    repaired(qtbot, win, "big-hole")
    m = win.model
    assert len(m.result.candidates) == 0 and len(m.repair.bridges) == 0
    assert [s.name for s in m.stages] == ["input", "bridges", "holes", "split", "darned"]
    assert win.bridges.table_model.rowCount() == 0
    win.timeline.last()
    assert win.scene.layers.meshes["patches"].n_cells == len(m.repair.new_faces) > 0
    win.timeline.first()
    assert "patches" not in win.scene.layers.meshes and win.scene.layers.actor("holes") is not None

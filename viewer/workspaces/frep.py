"""The F-rep workspace (issue 7 item 7): pick a bundled object or open a spec, triangulate it off
the GUI thread, and replay the recorded stages on a timeline (points, quads, holes highlighted,
filled, merged region, refined, faired) with the metrics beside and the min-angle histogram in a
plot dock.

Open it with ``FrepWorkspace(parent)``; ``open_demo(name)`` / ``open_spec(path)`` load an object
(the bundled sphere is loaded on construction unless ``demo=None``). Call ``shutdown()`` (or
close the widget) before it is destroyed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import (
    QApplication,
    QCheckBox,
    QComboBox,
    QDockWidget,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QProgressBar,
    QPushButton,
    QScrollArea,
    QSlider,
    QSpinBox,
    QStyle,
    QVBoxLayout,
    QWidget,
)
from pyvistaqt import QtInteractor

from algorithms.demos import all_demos
from algorithms.frep.objects import FRepObject, load_spec
from algorithms.frep.pipeline import FAIRINGS, WEIGHTS, FrepParams, FrepResult, Stage, triangulate_object
from algorithms.metrics import angle_stats, min_angles

from ..plotter_close import close_plotter
from ..to_pyvista import points, polylines, surface
from .common import AngleHistogram, JobRunner, debounce, stats_text

STAGE_TITLES = {
    "points": "sampled points (quadtree + ray bisection)",
    "quads": "linked quads ABCD → triangles",
    "holes": "holes: loops of one-face edges",
    "filled": "holes filled (minimum-weight, patches highlighted)",
    "region": "merged with the side faces (region to refine highlighted)",
    "refined": "refined: centroid splits + edge flips (new faces highlighted)",
    "faired": "faired (U2 = 0), projected and evened out (valence flips + CVT relaxation): the result",
}
PLAIN, HIGHLIGHT = "#c9d6df", "#f39c4a"


@dataclass(frozen=True, eq=False)
class FrepRun:
    """What the worker hands back: the run, its stages and each stage's per-triangle min angles."""

    name: str
    params: FrepParams
    result: FrepResult
    stages: list[Stage]
    angles: list[NDArray[np.float64]]


def triangulate(obj: FRepObject, params: FrepParams) -> FrepRun:
    """Runs in the pool thread: numpy only, no Qt or VTK."""
    r = triangulate_object(obj, params)
    stages = r.stages()
    angles = [min_angles(s.vertices, s.faces) if len(s.faces) else np.zeros(0) for s in stages]
    return FrepRun(obj.name, params, r, stages, angles)


def _f(x: float, digits: int = 3) -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.{digits}g}"


class FrepWorkspace(QWidget):
    """Triangulation of functionally defined objects, stage by stage."""

    def __init__(self, parent: QWidget | None = None, *, demo: str | None = "sphere") -> None:
        super().__init__(parent)
        self.setWindowTitle("Bridgefield - F-rep objects")
        self.resize(1400, 900)
        self.obj: FRepObject | None = None
        self.current: FrepRun | None = None
        self.error: str | None = None
        self._closed = False
        self._reset_camera = False
        self.runner = JobRunner(self)
        self.runner.finished.connect(self._on_result)
        self.runner.failed.connect(self._show_error)
        self.runner.busy_changed.connect(self._on_busy)
        self._recompute_timer = debounce(self, 350, self.recompute)
        app = QApplication.instance()
        if app is not None:  # a window destroyed with its parent gets no closeEvent
            app.aboutToQuit.connect(self.shutdown)
        self.play_timer = QTimer(self)
        self.play_timer.setInterval(800)
        self.play_timer.timeout.connect(self._play_step)

        inner = QMainWindow(self)
        inner.setWindowFlags(Qt.WindowType.Widget)
        self.inner = inner
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(inner)

        centre = QWidget()
        cl = QVBoxLayout(centre)
        cl.setContentsMargins(0, 0, 0, 0)
        self.plotter = QtInteractor(centre)
        self.plotter.set_background("white", top="#dfe7ee")
        cl.addWidget(self.plotter.interactor, 1)
        cl.addWidget(self._build_timeline())
        inner.setCentralWidget(centre)

        inner.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, self._dock("Object and parameters",
                                                                              self._build_controls()))
        self.metrics_label = QLabel("—")
        self.metrics_label.setTextFormat(Qt.TextFormat.RichText)
        self.metrics_label.setAlignment(Qt.AlignmentFlag.AlignTop | Qt.AlignmentFlag.AlignLeft)
        self.metrics_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setWidget(self.metrics_label)
        scroll.setMinimumWidth(330)
        self.metrics_dock = self._dock("Metrics", scroll)
        inner.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.metrics_dock)
        inner.resizeDocks([self.metrics_dock], [380], Qt.Orientation.Horizontal)
        hp = QWidget()
        hl = QVBoxLayout(hp)
        hl.setContentsMargins(4, 4, 4, 4)
        self.histogram = AngleHistogram(hp)
        self.stats_label = QLabel("—")
        self.stats_label.setWordWrap(True)
        hl.addWidget(self.histogram, 1)
        hl.addWidget(self.stats_label)
        self.hist_dock = self._dock("Min-angle histogram", hp)
        inner.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, self.hist_dock)
        inner.resizeDocks([self.hist_dock], [250], Qt.Orientation.Vertical)

        if demo is not None:
            self.open_demo(demo)

    # ---- construction ------------------------------------------------------------------------
    def _dock(self, title: str, widget: QWidget) -> QDockWidget:
        d = QDockWidget(title, self.inner)
        d.setObjectName(title)
        d.setWidget(widget)
        d.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetMovable
                      | QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        return d

    def _build_timeline(self) -> QWidget:
        w = QWidget()
        col = QVBoxLayout(w)
        col.setContentsMargins(6, 2, 6, 4)
        col.setSpacing(2)
        row = QHBoxLayout()
        col.addLayout(row)
        st = self.style()
        icon = st.standardIcon
        SP = QStyle.StandardPixmap
        self.first_btn = QPushButton(icon(SP.SP_MediaSkipBackward), "")
        self.prev_btn = QPushButton(icon(SP.SP_MediaSeekBackward), "")
        self.play_btn = QPushButton(icon(SP.SP_MediaPlay), "")
        self.next_btn = QPushButton(icon(SP.SP_MediaSeekForward), "")
        self.last_btn = QPushButton(icon(SP.SP_MediaSkipForward), "")
        for b, tip in ((self.first_btn, "first stage"), (self.prev_btn, "previous stage"), (self.play_btn, "play"),
                       (self.next_btn, "next stage"), (self.last_btn, "last stage")):
            b.setToolTip(tip)
            b.setFixedWidth(36)
        self.play_btn.setCheckable(True)
        self.stage_slider = QSlider(Qt.Orientation.Horizontal)
        self.stage_slider.setRange(0, 0)
        self.stage_slider.setPageStep(1)
        self.stage_slider.setTickPosition(QSlider.TickPosition.TicksBelow)
        self.stage_slider.setTickInterval(1)
        self.stage_label = QLabel("no stages yet")
        self.first_btn.clicked.connect(lambda: self.stage_slider.setValue(0))
        self.prev_btn.clicked.connect(lambda: self.stage_slider.setValue(self.stage_slider.value() - 1))
        self.next_btn.clicked.connect(lambda: self.stage_slider.setValue(self.stage_slider.value() + 1))
        self.last_btn.clicked.connect(lambda: self.stage_slider.setValue(self.stage_slider.maximum()))
        self.play_btn.toggled.connect(self._toggle_play)
        self.stage_slider.valueChanged.connect(self._show_stage)
        for b in (self.first_btn, self.prev_btn, self.play_btn, self.next_btn, self.last_btn):
            row.addWidget(b)
        row.addWidget(self.stage_slider, 1)
        col.addWidget(self.stage_label)
        return w

    def _build_controls(self) -> QWidget:
        w = QWidget()
        form = QFormLayout(w)
        self.demo_combo = QComboBox()
        self._demos = {n: d for n, d in all_demos().items() if d.kind == "frep"}
        for n, d in self._demos.items():
            self.demo_combo.addItem(n, n)
            self.demo_combo.setItemData(self.demo_combo.count() - 1, d.description, Qt.ItemDataRole.ToolTipRole)
        self.demo_combo.activated.connect(lambda i: self.open_demo(self.demo_combo.itemData(i)))
        open_btn = QPushButton("Open spec…")
        open_btn.clicked.connect(self._ask_spec)
        row = QHBoxLayout()
        row.addWidget(self.demo_combo, 1)
        row.addWidget(open_btn)
        form.addRow("Object", row)
        self.description = QLabel("")
        self.description.setWordWrap(True)
        form.addRow(self.description)
        self.qlev_spin = QSpinBox()
        self.qlev_spin.setRange(1, 10)
        self.qlev_spin.setValue(FrepParams.qlev)
        self.qlev_spin.setToolTip("Quadtree depth: S_xy = size / 2^QLEV")
        self.blev_spin = QSpinBox()
        self.blev_spin.setRange(1, 30)
        self.blev_spin.setValue(FrepParams.blev)
        self.blev_spin.setToolTip("Ray bisection depth: S_z = size / 2^BLEV")
        form.addRow("QLEV", self.qlev_spin)
        form.addRow("BLEV", self.blev_spin)
        self.weight_combo = QComboBox()
        self.weight_combo.addItems(list(WEIGHTS))
        self.weight_combo.setToolTip("Hole filling weight (minimum area or minimum edge length)")
        form.addRow("Fill weight", self.weight_combo)
        self.fairing_combo = QComboBox()
        self.fairing_combo.addItems(list(FAIRINGS))
        form.addRow("Fairing", self.fairing_combo)
        self.refine_check = QCheckBox("refine the filled region")
        self.refine_check.setChecked(True)
        form.addRow(self.refine_check)
        self.smooth_spin = QSpinBox()
        self.smooth_spin.setRange(0, 100)
        self.smooth_spin.setValue(FrepParams.smooth)
        self.smooth_spin.setToolTip("Rounds of isotropic improvement (valence flips + tangential CVT relaxation, "
                                    "each projected onto F = 0); 0 = the paper's pipeline")
        form.addRow("Even out", self.smooth_spin)
        for s in (self.qlev_spin, self.blev_spin, self.smooth_spin):
            s.valueChanged.connect(self._params_changed)
        for c in (self.weight_combo, self.fairing_combo):
            c.currentIndexChanged.connect(self._params_changed)
        self.refine_check.toggled.connect(self._params_changed)
        self.edges_check = QCheckBox("triangle edges")
        self.edges_check.setChecked(True)
        self.edges_check.toggled.connect(lambda _b: self._show_stage(self.stage_slider.value()))
        form.addRow(self.edges_check)

        self.progress = QProgressBar()
        self.progress.setRange(0, 0)  # busy indicator: the pipeline reports no fraction done
        self.progress.setVisible(False)
        self.cancel_btn = QPushButton("Cancel")
        self.cancel_btn.setToolTip("Drop the running computation (its result is discarded when it returns)")
        self.cancel_btn.setEnabled(False)
        self.cancel_btn.clicked.connect(self.cancel)
        prow = QHBoxLayout()
        prow.addWidget(self.progress, 1)
        prow.addWidget(self.cancel_btn)
        form.addRow(prow)
        self.status = QLabel("")
        self.status.setWordWrap(True)
        form.addRow(self.status)
        w.setMinimumWidth(280)
        return w

    # ---- loading -----------------------------------------------------------------------------
    def open_demo(self, name: str) -> None:
        d = self._demos.get(name)
        if d is None:
            self._show_error(f"unknown F-rep demo {name!r} (known: {', '.join(self._demos)})")
            return
        i = self.demo_combo.findData(name)
        if i >= 0:
            self.demo_combo.setCurrentIndex(i)
        self.open_spec(d.path)

    def open_spec(self, path: str | Path) -> None:
        try:
            obj = load_spec(path)
        except Exception as exc:  # shown to the user; the workspace keeps working
            self._show_error(str(exc))
            return
        self.obj = obj
        self.description.setText(obj.description or str(path))
        self.current = None
        self._recompute_timer.stop()
        self.recompute(reset_camera=True)

    def _ask_spec(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open an F-rep object spec", "", "Spec (*.json);;All files (*)")
        if path:
            self.demo_combo.setCurrentIndex(-1)
            self.open_spec(path)

    # ---- parameters and jobs -----------------------------------------------------------------
    def params(self) -> FrepParams:
        return FrepParams(qlev=self.qlev_spin.value(), blev=self.blev_spin.value(),
                          weight=self.weight_combo.currentText(), fairing=self.fairing_combo.currentText(),
                          refine=self.refine_check.isChecked(), smooth=self.smooth_spin.value())

    def _params_changed(self, *_args) -> None:
        self._recompute_timer.start()

    def recompute(self, *, reset_camera: bool = False) -> None:
        if self.obj is None or self._closed:
            return
        try:
            p = self.params()
        except ValueError as exc:
            self._show_error(str(exc))
            return
        self._reset_camera = reset_camera or self._reset_camera
        self.status.setText(f"triangulating {self.obj.name} (QLEV {p.qlev}, BLEV {p.blev})…")
        self.runner.submit(triangulate, self.obj, p)

    def cancel(self) -> None:
        self._recompute_timer.stop()
        self.runner.cancel()
        self.status.setText("cancelled (the running job's result will be dropped)")

    @property
    def busy(self) -> bool:
        return self.runner.busy or self._recompute_timer.isActive()

    def _on_busy(self, busy: bool) -> None:
        self.progress.setVisible(busy)
        self.cancel_btn.setEnabled(busy)

    def _show_error(self, text: str) -> None:
        self.error = text
        self.status.setText(f"<span style='color:#b00020'>{text}</span>")

    def _on_result(self, run: FrepRun) -> None:
        if self._closed:
            return
        self.current = run
        self.error = None
        r = run.result
        self.status.setText(f"{run.name}: {len(r.samples.points)} points, {len(r.loops)} holes, "
                            f"{len(r.faired.faces)} triangles in {r.timings.get('total', 0.0):.2f} s")
        self._fill_metrics()
        last = len(run.stages) - 1
        self.stage_slider.blockSignals(True)
        self.stage_slider.setRange(0, last)
        self.stage_slider.setValue(last)
        self.stage_slider.blockSignals(False)
        self._show_stage(last)
        if self._reset_camera:
            self.plotter.reset_camera()
            self.plotter.camera.zoom(1.1)
            self._reset_camera = False
            self.plotter.render()

    # ---- the timeline ------------------------------------------------------------------------
    def _toggle_play(self, on: bool) -> None:
        icon = self.style().standardIcon
        self.play_btn.setIcon(icon(QStyle.StandardPixmap.SP_MediaPause if on else QStyle.StandardPixmap.SP_MediaPlay))
        if on:
            if self.stage_slider.value() >= self.stage_slider.maximum():
                self.stage_slider.setValue(0)
            self.play_timer.start()
        else:
            self.play_timer.stop()

    def _play_step(self) -> None:
        if self.stage_slider.value() >= self.stage_slider.maximum():
            self.play_btn.setChecked(False)
            return
        self.stage_slider.setValue(self.stage_slider.value() + 1)

    def stage_index(self) -> int:
        return self.stage_slider.value()

    def _show_stage(self, k: int) -> None:
        run = self.current
        if run is None or self._closed or not 0 <= k < len(run.stages):
            return
        s = run.stages[k]
        pl = self.plotter
        if len(s.faces):
            hl = s.highlight if s.highlight is not None else np.zeros(len(s.faces), bool)
            pd = surface(s.vertices, s.faces, cell_data={"highlight": hl.astype(np.int64)})
            pl.add_mesh(pd, render=False, scalars="highlight", cmap=[PLAIN, HIGHLIGHT], clim=(0, 1), categories=True,
                        show_scalar_bar=False, name="stage", show_edges=self.edges_check.isChecked(),
                        edge_color="#5a6673", line_width=0.5, ambient=0.25)
        else:
            pl.add_mesh(points(s.vertices), render=False, color="#1f77b4", point_size=6, render_points_as_spheres=True,
                        name="stage")
        if s.loops:
            pl.add_mesh(polylines([s.vertices[lp] for lp in s.loops], closed=True), render=False, color="#d62728",
                        line_width=5, render_lines_as_tubes=True, name="loops")
        else:
            pl.remove_actor("loops", render=False)
        pl.render()
        n_hl = int(s.highlight.sum()) if s.highlight is not None else 0
        extra = f", {len(s.loops)} hole loops" if s.loops else (f", {n_hl} highlighted" if n_hl else "")
        self.stage_label.setText(f"{k + 1}/{len(run.stages)} {s.name}: {STAGE_TITLES.get(s.name, s.name)} — "
                                 f"{len(s.vertices)} vertices, {len(s.faces)} faces{extra}")
        final = run.angles[-1]
        if len(s.faces):
            self.histogram.show_angles(run.angles[k], label=s.name, overlay=final if k != len(run.stages) - 1
                                       else None, overlay_label="faired (result)", threshold=None)
            self.stats_label.setText(stats_text(angle_stats(run.angles[k]), label=s.name))
        else:
            self.histogram.show_angles(final, label="faired (result)")
            self.stats_label.setText(f"{s.name}: no triangles yet; showing the result. "
                                     + stats_text(angle_stats(final), label="faired"))

    # ---- metrics -----------------------------------------------------------------------------
    def _fill_metrics(self) -> None:
        run = self.current
        assert run is not None
        r, m = run.result, run.result.metrics
        t = m.topology
        a = m.angles
        rows = [
            ("<b>result</b>", ""),
            ("vertices / faces", f"{m.vertices} / {m.faces}"),
            ("watertight", "yes" if t.watertight else "no"),
            ("components / genus", f"{t.components} / {_f(t.genus)}" + (
                f" (expected {r.obj.genus})" if getattr(r.obj, "genus", None) is not None else "")),
            ("holes filled", f"{len(r.loops)} (sizes {', '.join(str(len(lp)) for lp in r.loops[:6])}"
                             f"{'…' if len(r.loops) > 6 else ''})" if r.loops else "0"),
            ("splits / flips", f"{r.splits} / {r.flips}"),
            ("<b>vertex deviation</b>", f"voxel S_xy = {_f(m.voxel)}"),
            ("mean / max |F|/|∇F|", f"{_f(m.deviation_mean)} / {_f(m.deviation_max)}"),
            ("max / voxel", _f(m.deviation_max / m.voxel if m.voxel else float("nan"))),
            ("projected mean / max", f"{_f(m.projected_mean)} / {_f(m.projected_max)}"),
            ("<b>normal deviation (°)</b>", ""),
            ("vertex mean / p95 / max", f"{_f(m.vertex_normal_mean)} / {_f(m.vertex_normal_p95)} / "
                                        f"{_f(m.vertex_normal_max)}"),
            ("face mean / p95 / max", f"{_f(m.face_normal_mean)} / {_f(m.face_normal_p95)} / {_f(m.face_normal_max)}"),
            ("<b>uniformity</b>", ""),
            ("edge-length CV", _f(m.edge_cv)),
            ("mean edge", _f(m.edge_mean)),
            ("<b>angles (triangle min)</b>", ""),
            ("min / 1st pct / median", f"{_f(a.min)}° / {_f(a.p01)}° / {_f(a.median)}°"),
            ("below 20° / 30°", f"{100 * a.below_20:.2f} % / {100 * a.below_30:.2f} %"),
            ("<b>time (s)</b>", ""),
        ] + [(k, f"{v:.3f}") for k, v in r.timings.items()]
        html = "<table cellspacing='2'>" + "".join(
            f"<tr><td>{k}</td><td align='right'>{v}</td></tr>" for k, v in rows) + "</table>"
        self.metrics_label.setText(html)

    # ---- closing -----------------------------------------------------------------------------
    def shutdown(self) -> None:
        """Stop the timers and the worker, then release the render window. Idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self.play_timer.stop()
            self._recompute_timer.stop()
            self.runner.shutdown()
            close_plotter(self.plotter)
        except RuntimeError:  # the Qt objects were already deleted with a parent
            pass

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        self.shutdown()
        super().closeEvent(event)

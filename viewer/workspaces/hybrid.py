"""The hybrid-surface workspace (issue 6 item 7): pick a bundled surface or open a spec, mesh it
off the GUI thread, see the 3D surface coloured by per-triangle min angle, the min-angle
histogram (before / after refinement) in a dock, and the border curve with the (u, v) mesh beside.

Open it with ``HybridWorkspace(parent)``; ``open_demo(name)`` / ``open_spec(path)`` load a
surface (the first bundled one is loaded on construction unless ``demo=None``). Call
``shutdown()`` (or close the widget) before it is destroyed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from numpy.typing import NDArray
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QApplication,
    QCheckBox,
    QComboBox,
    QDockWidget,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QProgressBar,
    QPushButton,
    QSlider,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)
from pyvistaqt import QtInteractor

from algorithms.demos import all_demos
from algorithms.hybrid.mesher import HybridParams, HybridResult, mesh_hybrid
from algorithms.hybrid.spec import Spec, load_spec

from ..plotter_close import close_plotter
from ..to_pyvista import polylines, surface
from .common import AngleHistogram, JobRunner, debounce, stats_text

AFTER_COLOUR, BEFORE_COLOUR = "#4c8cbf", "#e07b39"  # the same colour for a stage, as bars or outline
MIN_ANGLE_MAX = 34.0  # RefineParams refuses more (refinement does not terminate above ~34°)


@dataclass(frozen=True)
class MeshedSurface:
    """What the worker hands back: the run and the border curves mapped to 3D (for display)."""

    name: str
    params: HybridParams
    result: HybridResult
    border_3d: list[NDArray[np.float64]]
    border_uv: list[NDArray[np.float64]]
    report: dict


def mesh_surface(spec: Spec, params: HybridParams) -> MeshedSurface:
    """Runs in the pool thread: numpy only, no Qt or VTK."""
    r = mesh_hybrid(spec.model, params)
    b = r.border
    chains_uv = [b.points[np.asarray(c)] for c in b.polylines if len(c) > 1]
    chains_3d = [np.asarray(spec.model.surface(c[:, 0], c[:, 1]), dtype=np.float64).reshape(-1, 3)
                 for c in chains_uv]
    return MeshedSurface(spec.model.name, params, r, chains_3d, chains_uv, r.report())


class UVCanvas(FigureCanvasQTAgg):
    """The parameter-space view: the (u, v) triangulation and the border polylines."""

    def __init__(self, parent=None) -> None:
        self.figure = Figure(figsize=(4, 4), dpi=90, layout="constrained")
        super().__init__(self.figure)
        self.setParent(parent)
        self.ax = self.figure.add_subplot(111)
        self.setMinimumWidth(220)

    def show_mesh(self, uv: NDArray, faces: NDArray, border: list[NDArray], domain: tuple, title: str) -> None:
        ax = self.ax
        ax.clear()
        if len(faces):
            tri = uv[faces]
            segs = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
            ax.add_collection(LineCollection(segs, colors="#7a8793", linewidths=0.3))
        if border:
            ax.add_collection(LineCollection(border, colors="#d62728", linewidths=1.4))
        a, b, c, d = domain
        ax.plot([a, b, b, a, a], [c, c, d, d, c], color="#444444", linewidth=0.8, linestyle="--")
        pad_u, pad_v = 0.03 * (b - a), 0.03 * (d - c)
        ax.set_xlim(a - pad_u, b + pad_u)
        ax.set_ylim(c - pad_v, d + pad_v)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("u")
        ax.set_ylabel("v")
        ax.set_title(title, fontsize=8)
        self.draw_idle()


class HybridWorkspace(QWidget):
    """Hybrid parametric + implicit surface meshing, explored."""

    def __init__(self, parent: QWidget | None = None, *, demo: str | None = "bezier-hole") -> None:
        super().__init__(parent)
        self.setWindowTitle("Bridgefield - hybrid surfaces")
        self.resize(1400, 900)
        self.spec: Spec | None = None
        self.current: MeshedSurface | None = None
        self.error: str | None = None
        self._closed = False
        self.runner = JobRunner(self)
        self.runner.finished.connect(self._on_result)
        self.runner.failed.connect(self._on_failed)
        self.runner.busy_changed.connect(self._on_busy)
        self._recompute_timer = debounce(self, 350, self.recompute)
        app = QApplication.instance()
        if app is not None:  # a window destroyed with its parent gets no closeEvent
            app.aboutToQuit.connect(self.shutdown)

        inner = QMainWindow(self)
        inner.setWindowFlags(Qt.WindowType.Widget)
        inner.setDockOptions(QMainWindow.DockOption.AllowTabbedDocks | QMainWindow.DockOption.AnimatedDocks)
        self.inner = inner
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(inner)

        self.plotter = QtInteractor(inner)
        self.plotter.set_background("white", top="#dfe7ee")
        inner.setCentralWidget(self.plotter.interactor)

        inner.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, self._dock("Surface and parameters",
                                                                              self._build_controls()))
        self.uv_canvas = UVCanvas()
        self.uv_dock = self._dock("Parameter space (u, v)", self.uv_canvas)
        inner.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.uv_dock)
        hist_panel = QWidget()
        hl = QVBoxLayout(hist_panel)
        hl.setContentsMargins(4, 4, 4, 4)
        self.histogram = AngleHistogram(hist_panel)
        self.stats_label = QLabel("—")
        self.stats_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.stats_label.setWordWrap(True)
        hl.addWidget(self.histogram, 1)
        hl.addWidget(self.stats_label)
        self.hist_dock = self._dock("Min-angle histogram", hist_panel)
        inner.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, self.hist_dock)
        inner.resizeDocks([self.uv_dock], [420], Qt.Orientation.Horizontal)
        inner.resizeDocks([self.hist_dock], [260], Qt.Orientation.Vertical)

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

    def _build_controls(self) -> QWidget:
        w = QWidget()
        form = QFormLayout(w)
        self.demo_combo = QComboBox()
        self._demos = {n: d for n, d in all_demos().items() if d.kind == "hybrid"}
        for n, d in self._demos.items():
            self.demo_combo.addItem(n, n)
            self.demo_combo.setItemData(self.demo_combo.count() - 1, d.description, Qt.ItemDataRole.ToolTipRole)
        self.demo_combo.activated.connect(lambda i: self.open_demo(self.demo_combo.itemData(i)))
        open_btn = QPushButton("Open spec…")
        open_btn.clicked.connect(self._ask_spec)
        row = QHBoxLayout()
        row.addWidget(self.demo_combo, 1)
        row.addWidget(open_btn)
        form.addRow("Surface", row)
        self.description = QLabel("")
        self.description.setWordWrap(True)
        form.addRow(self.description)

        # min-angle threshold: a slider and a spin box kept in step
        self.threshold_slider = QSlider(Qt.Orientation.Horizontal)
        self.threshold_slider.setRange(0, int(MIN_ANGLE_MAX))
        self.threshold_spin = QDoubleSpinBox()
        self.threshold_spin.setRange(0.0, MIN_ANGLE_MAX)
        self.threshold_spin.setDecimals(1)
        self.threshold_spin.setSingleStep(1.0)
        self.threshold_spin.setSuffix(" °")
        self.threshold_spin.setValue(30.0)
        self.threshold_slider.setValue(30)
        self.threshold_slider.valueChanged.connect(lambda v: self.threshold_spin.setValue(float(v)))
        self.threshold_spin.valueChanged.connect(self._threshold_changed)
        trow = QHBoxLayout()
        trow.addWidget(self.threshold_slider, 1)
        trow.addWidget(self.threshold_spin)
        form.addRow("Min angle", trow)

        self.max_edge_spin = QDoubleSpinBox()
        self.max_edge_spin.setRange(0.0, 1e6)
        self.max_edge_spin.setDecimals(3)
        self.max_edge_spin.setSingleStep(0.01)
        self.max_edge_spin.setSpecialValueText("no limit")
        self.max_edge_spin.setToolTip("Longest 3D edge (0: no limit)")
        self.max_edge_spin.valueChanged.connect(self._params_changed)
        form.addRow("Max edge", self.max_edge_spin)
        self.cells_spin = QSpinBox()
        self.cells_spin.setRange(4, 400)
        self.cells_spin.setValue(40)
        self.cells_spin.setToolTip("Background grid cells along the longer direction (Stage I)")
        self.cells_spin.valueChanged.connect(self._params_changed)
        form.addRow("Grid cells", self.cells_spin)
        self.chord_spin = QDoubleSpinBox()
        self.chord_spin.setRange(0.0, 0.999)
        self.chord_spin.setDecimals(3)
        self.chord_spin.setSingleStep(0.005)
        self.chord_spin.setValue(0.98)
        self.chord_spin.setToolTip("Curvature criterion: refine while chord / arc is below this (0: off)")
        self.chord_spin.valueChanged.connect(self._params_changed)
        form.addRow("Chord / arc", self.chord_spin)
        self.deviation_spin = QDoubleSpinBox()
        self.deviation_spin.setRange(0.0, 1e3)
        self.deviation_spin.setDecimals(5)
        self.deviation_spin.setSingleStep(0.0005)
        self.deviation_spin.setSpecialValueText("spec's")
        self.deviation_spin.setToolTip("Curvature criterion as a chordal error: refine a triangle or border segment "
                                       "farther than this from the surface (model units; 0: the spec's setting)")
        self.deviation_spin.valueChanged.connect(self._params_changed)
        form.addRow("Max deviation", self.deviation_spin)
        self.coarsen_spin = QDoubleSpinBox()
        self.coarsen_spin.setRange(0.0, 59.0)
        self.coarsen_spin.setDecimals(1)
        self.coarsen_spin.setSingleStep(1.0)
        self.coarsen_spin.setSuffix(" °")
        self.coarsen_spin.setSpecialValueText("off")
        self.coarsen_spin.setValue(HybridParams.coarsen_angle)
        self.coarsen_spin.setToolTip("Coarsening after refinement: remove the vertices the size criteria do not need "
                                     "while every new triangle keeps at least this smallest angle (at least the "
                                     "min-angle threshold; off: the refined mesh as it is)")
        self.coarsen_spin.valueChanged.connect(self._params_changed)
        form.addRow("Coarsen angle", self.coarsen_spin)

        self.stage_combo = QComboBox()
        self.stage_combo.addItem("after refinement (Stage III)", "after")
        self.stage_combo.addItem("before refinement (Stage II)", "before")
        self.stage_combo.currentIndexChanged.connect(lambda _i: self._redraw())
        form.addRow("Show", self.stage_combo)
        self.edges_check = QCheckBox("triangle edges")
        self.edges_check.setChecked(True)
        self.border_check = QCheckBox("border curve")
        self.border_check.setChecked(True)
        self.corner_check = QCheckBox("trim-corner exceptions")
        self.corner_check.setChecked(True)
        self.overlay_check = QCheckBox("overlay the other stage on the histogram")
        self.overlay_check.setChecked(True)
        self.share_check = QCheckBox("histogram in % of each stage's triangles")
        for c in (self.edges_check, self.border_check, self.corner_check, self.overlay_check, self.share_check):
            c.toggled.connect(lambda _b: self._redraw())
            form.addRow(c)

        self.progress = QProgressBar()
        self.progress.setRange(0, 0)  # busy indicator: the mesher reports no fraction done
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
        self.status.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        form.addRow(self.status)
        w.setMinimumWidth(300)
        return w

    # ---- loading -----------------------------------------------------------------------------
    def open_demo(self, name: str) -> None:
        d = self._demos.get(name)
        if d is None:
            self._show_error(f"unknown hybrid demo {name!r} (known: {', '.join(self._demos)})")
            return
        i = self.demo_combo.findData(name)
        if i >= 0:
            self.demo_combo.setCurrentIndex(i)
        self.open_spec(d.path)

    def open_spec(self, path: str | Path) -> None:
        try:
            spec = load_spec(path)
        except Exception as exc:  # shown to the user; the workspace keeps working
            self._show_error(str(exc))
            return
        self.spec = spec
        self.description.setText(spec.model.description or str(path))
        p = spec.params()
        for wdg, val in ((self.threshold_spin, p.min_angle), (self.max_edge_spin, p.max_edge or 0.0),
                         (self.cells_spin, p.cells), (self.chord_spin, p.chord_arc),
                         (self.deviation_spin, p.max_deviation or 0.0), (self.coarsen_spin, p.coarsen_angle),
                         (self.threshold_slider, int(round(p.min_angle)))):
            wdg.blockSignals(True)
            wdg.setValue(val)
            wdg.blockSignals(False)
        self.current = None
        self._recompute_timer.stop()
        self.recompute(reset_camera=True)

    def _ask_spec(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open a hybrid surface spec", "", "Spec (*.json);;All files (*)")
        if path:
            self.demo_combo.setCurrentIndex(-1)
            self.open_spec(path)

    # ---- parameters --------------------------------------------------------------------------
    def params(self) -> HybridParams:
        assert self.spec is not None
        me = self.max_edge_spin.value()
        a, ca = self.threshold_spin.value(), self.coarsen_spin.value()
        return self.spec.params(min_angle=a, max_edge=me if me > 0 else None,
                                cells=self.cells_spin.value(), chord_arc=self.chord_spin.value(),
                                max_deviation=self.deviation_spin.value() or None,
                                coarsen_angle=max(ca, a) if ca > 0 else 0.0)

    def _threshold_changed(self, value: float) -> None:
        self.threshold_slider.blockSignals(True)
        self.threshold_slider.setValue(int(round(value)))
        self.threshold_slider.blockSignals(False)
        if self.current is not None:  # the threshold line moves at once; the mesh follows
            self._draw_histogram()
        self._params_changed()

    def _params_changed(self, *_args) -> None:
        self._recompute_timer.start()  # debounced: one run when the edits stop

    def recompute(self, *, reset_camera: bool = False) -> None:
        if self.spec is None or self._closed:
            return
        try:
            p = self.params()
        except ValueError as exc:
            self._show_error(str(exc))
            return
        self._reset_camera = reset_camera or getattr(self, "_reset_camera", False)
        self.status.setText(f"meshing {self.spec.model.name} (min angle {p.min_angle:g}°)…")
        self.runner.submit(mesh_surface, self.spec, p)

    def cancel(self) -> None:
        self._recompute_timer.stop()
        self.runner.cancel()
        self.status.setText("cancelled (the running job's result will be dropped)")

    @property
    def busy(self) -> bool:
        return self.runner.busy or self._recompute_timer.isActive()

    # ---- results -----------------------------------------------------------------------------
    def _on_busy(self, busy: bool) -> None:
        self.progress.setVisible(busy)
        self.cancel_btn.setEnabled(busy)

    def _on_failed(self, text: str) -> None:
        self._show_error(text)

    def _show_error(self, text: str) -> None:
        self.error = text
        self.status.setText(f"<span style='color:#b00020'>{text}</span>")

    def _on_result(self, m: MeshedSurface) -> None:
        if self._closed:
            return
        self.current = m
        self.error = None
        r = m.result
        t = r.timings
        c = m.report["counts"]
        self.status.setText(
            f"{m.name}: {c['triangles_initial']} → {c['triangles_final']} triangles, "
            f"{c['inserted_circumcentres']} circumcentres, {c['border_splits']} border splits, "
            f"{len(r.corner_triangles)} trim-corner exceptions; {t.get('total', 0.0):.2f} s "
            f"(I {t.get('stage1_border', 0):.2f}, II {t.get('stage2_cdt', 0):.2f}, "
            f"III {t.get('stage3_refine', 0):.2f})")
        self._redraw()
        if getattr(self, "_reset_camera", False):
            self.plotter.reset_camera()
            self.plotter.camera.zoom(1.1)
            self._reset_camera = False
        self.plotter.render()

    def _stage(self) -> str:
        return self.stage_combo.currentData() or "after"

    def _redraw(self) -> None:
        m = self.current
        if m is None or self._closed:
            return
        r = m.result
        after = self._stage() == "after"
        pts, faces, ang = ((r.points, r.faces, r.min_angle_after) if after
                           else (r.initial_points, r.initial_faces, r.min_angle_before))
        pd = surface(pts, faces, cell_data={"min angle (°)": ang})
        self.plotter.add_mesh(pd, render=False, scalars="min angle (°)", cmap="RdYlGn", clim=(0.0, 60.0),
                              name="surface",
                              show_edges=self.edges_check.isChecked() and len(faces) < 60000,
                              edge_color="#404a55", line_width=0.4,
                              ambient=0.3, diffuse=0.75,
                              scalar_bar_args={"title": "triangle min angle (°)", "n_labels": 7, "fmt": "%.0f",
                                               "vertical": False, "position_x": 0.25, "position_y": 0.03,
                                               "height": 0.07, "width": 0.5, "color": "black"})
        if self.border_check.isChecked() and m.border_3d:
            self.plotter.add_mesh(polylines(m.border_3d), render=False, color="#1f3fbf", line_width=3, name="border")
        else:
            self.plotter.remove_actor("border", render=False)
        if after and self.corner_check.isChecked() and len(r.corner_triangles):
            pc = surface(r.points, r.faces[r.corner_triangles])
            self.plotter.add_mesh(pc, render=False, style="wireframe", color="black", line_width=2.5, name="corners")
        else:
            self.plotter.remove_actor("corners", render=False)
        uv, uvf = (r.uv, r.faces) if after else (r.initial_uv, r.initial_faces)
        self.uv_canvas.show_mesh(uv, uvf, m.border_uv, r.model.surface.domain,
                                 f"{m.name}: {'refined' if after else 'Stage II'} mesh in (u, v), "
                                 f"{len(uvf)} triangles; border in red")
        self._draw_histogram()
        self.plotter.render()

    def _draw_histogram(self) -> None:
        m = self.current
        if m is None:
            return
        r = m.result
        after = self._stage() == "after"
        main, other = (r.min_angle_after, r.min_angle_before) if after else (r.min_angle_before, r.min_angle_after)
        self.histogram.show_angles(main, label="after" if after else "before", overlay=other,
                                   overlay_label="before" if after else "after",
                                   threshold=self.threshold_spin.value(), show_overlay=self.overlay_check.isChecked(),
                                   colour=AFTER_COLOUR if after else BEFORE_COLOUR,
                                   overlay_colour=BEFORE_COLOUR if after else AFTER_COLOUR,
                                   share=self.share_check.isChecked())
        self.stats_label.setText(stats_text(r.stats_after, label=f"after (threshold {m.params.min_angle:g}°)") + "\n"
                                 + stats_text(r.stats_before, label="before") + "\n"
                                 + stats_text(r.stats_excluding_corners, label="after, trim corners excepted"))

    # ---- closing -----------------------------------------------------------------------------
    def shutdown(self) -> None:
        """Stop the timer and the worker, then release the render window. Idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self._recompute_timer.stop()
            self.runner.shutdown()
            close_plotter(self.plotter)
        except RuntimeError:  # the Qt objects were already deleted with a parent
            pass

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        self.shutdown()
        super().closeEvent(event)

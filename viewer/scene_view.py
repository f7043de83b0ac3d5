"""The 3D view: a QtInteractor that redraws from the model (VTK calls on the GUI thread only).

Model signals drive the named layers of :class:`viewer.scene.SceneLayers` (replaced or updated
in place). Renders are coalesced: many changes in one pass of the event loop render once.
A click (``P`` key or the picker) goes through :meth:`SceneView.on_pick`, which selects the
bridge under the point or asks to trace a force line from the nearest boundary point.
"""

from __future__ import annotations

import time

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal
from PySide6.QtOpenGLWidgets import QOpenGLWidget
from pyvistaqt import QtInteractor

from .plotter_close import close_plotter
from .scene import SceneLayers

MULTI_SAMPLES = 1  # MSAA multiplies the per-pixel cost of software GL (Xvfb + llvmpipe) for little gain


class SceneView(QObject):
    pickedBoundary = Signal(int)  # a boundary vertex was clicked: trace from it
    pickedBridge = Signal(int)  # a bridge was clicked: select it

    def __init__(self, model, parent_widget, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.plotter = QtInteractor(parent_widget, auto_update=False, multi_samples=MULTI_SAMPLES)
        self.plotter.setAcceptDrops(False)  # the window handles dropped files
        self.plotter.set_background("white", top="#dfe7ee")
        self.layers = SceneLayers(self.plotter)
        self.renders = 0
        self.render_seconds = 0.0
        self._render_timer = QTimer(self)
        self._render_timer.setSingleShot(True)
        self._render_timer.timeout.connect(self.render_now)
        model.inputChanged.connect(self._input_changed)
        model.resultChanged.connect(self._result_changed)
        model.selectionChanged.connect(self._selection_changed)
        model.lineChanged.connect(self._line_changed)
        model.frameChanged.connect(self._frame_changed)
        model.repairChanged.connect(self._repair_changed)
        model.stageChanged.connect(self._stage_changed)
        model.timelineModeChanged.connect(self._timeline_mode_changed)
        self.plotter.enable_point_picking(callback=self.on_pick, show_message=False, show_point=False,
                                          left_clicking=False, use_picker=True, pickable_window=False)

    @property
    def widget(self):
        return self.plotter.interactor

    # ---------------------------------------------------------------- rendering
    def request_render(self) -> None:
        if not self._render_timer.isActive():
            self._render_timer.start(0)

    def render_now(self) -> None:
        """Render the scene once. A shown view is asked to repaint (its paintGL renders): calling
        the render window directly would render twice (pyvistaqt's paintGL always renders, and a
        finished render schedules a paint)."""
        if getattr(self.plotter, "_closed", False):
            return
        t = time.perf_counter()
        if self.plotter.isVisible() and getattr(self.plotter, "_rendered", False):
            QOpenGLWidget.update(self.plotter)
        else:
            self.plotter.render()
        self.render_seconds += time.perf_counter() - t
        self.renders += 1

    def grab(self) -> np.ndarray:
        """(H, W, 3) uint8: the view as shown now (Qt grabs the widget's framebuffer, which
        renders it; pyvista's screenshot can return the previous frame with a QOpenGLWidget)."""
        from PySide6.QtGui import QImage

        self._render_timer.stop()
        img = self.plotter.interactor.grabFramebuffer().convertToFormat(QImage.Format_RGB888)
        w, h, bpl = img.width(), img.height(), img.bytesPerLine()
        arr = np.frombuffer(img.constBits(), dtype=np.uint8, count=h * bpl).reshape(h, bpl)
        return arr[:, : w * 3].reshape(h, w, 3).copy()

    def save_png(self, path: str) -> None:
        import imageio.v2 as imageio

        imageio.imwrite(path, self.grab())

    def stop(self) -> None:
        self._render_timer.stop()

    # ---------------------------------------------------------------- model -> layers
    def _input_changed(self) -> None:
        if self.model.icadm is None:
            return
        self.layers.draw_model(self.model.icadm, self.model.frames)
        self.layers.frame_camera()
        self.request_render()

    def _result_changed(self, result) -> None:
        self.layers.draw_result(result, repair=self.model.repair)  # the camera stays where it is
        self.request_render()

    def _repair_changed(self, repair) -> None:
        if self.model.result is not None:  # kept / rejected now come from the repair
            self.layers.draw_result(self.model.result, repair=repair)
            self.layers.draw_selection(self.model.result, self.model.selection)
        if self.model.timeline_mode == "stages" and self.model.stages:
            self.layers.draw_stage(self.model.stages[self.model.stage])
        else:
            self.layers.draw_stage(None)
            self.layers.draw_repair(repair)
        self.request_render()

    def _stage_changed(self, k: int) -> None:
        if self.model.timeline_mode == "stages" and 0 <= k < len(self.model.stages):
            self.layers.draw_stage(self.model.stages[k])
            self.request_render()

    def _timeline_mode_changed(self, mode: str) -> None:
        self.layers.set_stage_mode(mode == "stages")
        if mode == "line":
            self.layers.draw_stage(None)
            self.layers.draw_repair(self.model.repair)
        self.request_render()

    def _selection_changed(self, index: int) -> None:
        self.layers.draw_selection(self.model.result, index)
        self.request_render()

    def _line_changed(self, line) -> None:
        self.layers.set_line(line)
        self.request_render()

    def _frame_changed(self, k: int) -> None:
        self.layers.set_frame(k)
        self.request_render()

    def set_layer_visible(self, layer: str, on: bool) -> None:
        self.layers.set_visible(layer, on)
        self.request_render()

    def set_playing(self, on: bool) -> None:
        """While the timeline plays, draw the islands without their triangle edges (the costliest
        pass of software GL); the edges come back when it stops."""
        if self.layers.set_fast(on):
            self.request_render()

    # ---------------------------------------------------------------- picking
    def on_pick(self, point, *_) -> None:
        """The picker's handler (also called by tests): a bridge near the point is selected,
        otherwise the nearest boundary vertex starts a trace."""
        if point is None or self.model.icadm is None or not self.model.frames:
            return
        p = np.asarray(point, dtype=np.float64).reshape(3)
        scale = self.layers.scale
        bi, bd = self.layers.nearest_bridge(p) if self.layers.shown("bridges") else (-1, np.inf)
        allp = np.vstack([f.points for f in self.model.frames])
        allv = np.concatenate([f.vertices for f in self.model.frames])
        d = np.linalg.norm(allp - p, axis=1)
        j = int(np.argmin(d))
        if bi >= 0 and bd < 0.01 * scale and bd < d[j]:
            self.pickedBridge.emit(bi)
        elif d[j] < 0.05 * scale:
            self.pickedBoundary.emit(int(allv[j]))

    # ---------------------------------------------------------------- camera
    def camera_state(self) -> dict:
        c = self.plotter.camera
        return {"position": list(map(float, c.position)), "focal_point": list(map(float, c.focal_point)),
                "view_up": list(map(float, c.up)), "view_angle": float(c.view_angle),
                "parallel": bool(c.parallel_projection)}

    def set_camera_state(self, s: dict) -> None:
        c = self.plotter.camera
        c.position = s["position"]
        c.focal_point = s["focal_point"]
        c.up = s["view_up"]
        if "view_angle" in s:
            c.view_angle = s["view_angle"]
        c.parallel_projection = bool(s.get("parallel", False))
        self.plotter.renderer.ResetCameraClippingRange()
        self.request_render()

    def close(self) -> None:
        self.stop()
        close_plotter(self.plotter)

"""Compare: two linked side-by-side views of the same input with different parameters.

One QtInteractor with two renderers (``shape=(1, 2)``) whose cameras are linked, so rotating
one rotates both. Each side computes its own bridges in the worker; both bridge layers share
one colour range so their colours compare. Presets follow the papers (light vs full mode;
k_i = 0 vs k_i = 1 as in Figure 12; the simple vs the predictor-corrector tracer).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QMainWindow, QVBoxLayout, QWidget
from pyvistaqt import QtInteractor

from . import jobs
from .plotter_close import close_plotter
from .scene import SceneLayers, kept_mask, qualities
from .worker import Worker

PRESETS = {
    "light vs full mode": ({"mode": "light"}, {"mode": "full"}),
    "k_i = 0 vs k_i = 1 (Figure 12)": ({"ki": 0.0}, {"ki": 1.0}),
    "simple vs predictor-corrector tracer": ({"tracer": "simple"}, {"tracer": "predictor-corrector"}),
}


class CompareWindow(QMainWindow):
    def __init__(self, model, find, parent=None, *, runner=None) -> None:
        super().__init__(parent)
        self.setWindowFlag(Qt.Window, True)
        self.setWindowTitle("Bridgefield - compare")
        self.resize(1300, 650)
        self.model = model
        self.find = find
        self.runner = runner  # the main window's worker processes (None: worker threads)
        self.results: list = [None, None]
        self.worker = Worker(self)
        central = QWidget()
        lay = QVBoxLayout(central)
        top = QHBoxLayout()
        top.addWidget(QLabel("Compare"))
        self.preset = QComboBox()
        self.preset.addItems(list(PRESETS))
        top.addWidget(self.preset)
        self.info = QLabel("")
        top.addWidget(self.info, 1)
        lay.addLayout(top)
        self.plotter = QtInteractor(central, shape=(1, 2), auto_update=False)
        self.plotter.setAcceptDrops(False)
        self.plotter.set_background("white", top="#dfe7ee")
        lay.addWidget(self.plotter.interactor, 1)
        self.setCentralWidget(central)
        self.sides = [SceneLayers(self.plotter, subplot=(0, i), bar_suffix=" " * (i + 1)) for i in range(2)]
        for s in self.sides:
            s.draw_model(model.icadm, model.frames)
        self.plotter.link_views()
        self.sides[0].frame_camera()
        self.worker.finished.connect(self._landed)
        self.worker.failed.connect(lambda k, msg: self.info.setText(f"{k}: {msg.splitlines()[0]}"))
        self.preset.currentTextChanged.connect(self.compute)
        model.paramsChanged.connect(lambda *_: self.compute())
        self.compute()

    def side_params(self):
        a, b = PRESETS[self.preset.currentText()]
        p = self.model.params
        return replace(p, **a), replace(p, **b)

    def compute(self, *_):
        self.results = [None, None]
        for i, params in enumerate(self.side_params()):
            self.sides[i].draw_result(None)
            self.worker.submit(f"side{i}", jobs.bridges_job(self.find, self.model.icadm, params, self.runner))
        self.info.setText("computing…")

    def _landed(self, kind: str, result, seconds: float) -> None:
        i = int(kind[-1])
        model, params, bridges = result
        if model is not self.model.icadm or params != self.side_params()[i]:
            return
        self.results[i] = bridges
        if all(r is not None for r in self.results):
            qs = [qualities(r)[kept_mask(r)] for r in self.results if len(r.candidates)]
            qs = [q for q in qs if len(q)]
            clim = (float(min(q.min() for q in qs)), float(max(q.max() for q in qs))) if qs else None
            for k, (side, r) in enumerate(zip(self.sides, self.results)):
                side.draw_result(r, clim=clim)
                p = self.side_params()[k]
                arrived = int(np.sum(kept_mask(r))) if len(r.candidates) else 0
                self.plotter.subplot(0, k)
                self.plotter.add_text(f"{p.mode}, k_i={p.ki:g}, {p.tracer}: {arrived}/{len(r.candidates)} arrived",
                                      font_size=10, name="label", color="black")
            self.info.setText("same colour scale on both sides; cameras linked")
            self.plotter.render()

    def closeEvent(self, event) -> None:  # noqa: N802
        self.worker.shutdown()
        close_plotter(self.plotter)
        super().closeEvent(event)

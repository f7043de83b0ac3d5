"""The Parameters dock: mode, k_i (slider and spin box), k_t, tracer, step, threshold, L_c, and
the repair's darning method.

Widgets write through the model (``ExplorerModel.set_params``); the model's ``paramsChanged``
puts the values back in the widgets (undo/redo, sessions). A slider drag is one undo step.
"""

from __future__ import annotations

from dataclasses import replace

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSlider,
    QVBoxLayout,
    QWidget,
)

from algorithms.params import MODES, TRACERS, FieldParams
from algorithms.repair import DARNING

from ..scene import LAYER_TITLES, LAYERS

KI_MAX = 3.0
KI_TICKS = 300  # slider resolution: 0.01


class ParametersPanel(QWidget):
    invalid = Signal(str)  # a value the parameters refused (message names the parameter)
    layerToggled = Signal(str, bool)

    def __init__(self, model, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self._drag_start: FieldParams | None = None
        outer = QVBoxLayout(self)
        form = QFormLayout()
        outer.addLayout(form)
        self.form = form

        self.mode = QComboBox()
        self.mode.addItems(MODES)
        self.mode.setToolTip("light (M1): no shielding, no free points; full (M2): shielding (15) + free points (4)")
        form.addRow("Mode", self.mode)

        row = QHBoxLayout()
        self.ki_slider = QSlider(Qt.Horizontal)
        self.ki_slider.setRange(0, KI_TICKS)
        self.ki_slider.setPageStep(25)
        self.ki_slider.setToolTip("k_i, factor of interpolation in (9)-(10)")
        self.ki_spin = QDoubleSpinBox()
        self.ki_spin.setRange(0.0, 100.0)
        self.ki_spin.setDecimals(2)
        self.ki_spin.setSingleStep(0.05)
        row.addWidget(self.ki_slider, 1)
        row.addWidget(self.ki_spin)
        form.addRow("k_i", row)

        self.kt = QDoubleSpinBox()
        self.kt.setRange(0.01, 0.99)
        self.kt.setSingleStep(0.05)
        self.kt.setToolTip("k_t, trust of free-point coordinates (full mode): G(0) = k_t/(1-k_t)")
        form.addRow("k_t", self.kt)

        self.tracer = QComboBox()
        self.tracer.addItems(TRACERS)
        form.addRow("Tracer", self.tracer)

        self.step = QDoubleSpinBox()
        self.step.setRange(0.0, 1e6)
        self.step.setDecimals(4)
        self.step.setSingleStep(0.005)
        self.step.setSpecialValueText("auto")
        self.step.setToolTip("tracing step in model units (auto = step_factor x L_c)")
        form.addRow("Step", self.step)

        self.threshold = QDoubleSpinBox()
        self.threshold.setRange(0.0, 0.99)
        self.threshold.setDecimals(3)
        self.threshold.setSingleStep(0.005)
        self.threshold.setToolTip("a line stops as too weak when |H n| < threshold x |H n| at its start")
        form.addRow("Threshold", self.threshold)

        self.lc = QDoubleSpinBox()
        self.lc.setRange(0.0, 1e6)
        self.lc.setDecimals(4)
        self.lc.setSingleStep(0.01)
        self.lc.setSpecialValueText("auto")
        self.lc.setToolTip("L_c, characteristic value of the discontinuity (auto: §6)")
        form.addRow("L_c", self.lc)

        self.darning = QComboBox()
        self.darning.addItems(DARNING)
        self.darning.setToolTip("how the repair fills each simple hole: fan (the paper's), liepa (minimum-weight "
                                "triangulation), liepa-fair (+ refinement and fairing). Used by Repair (F6).")
        form.addRow("Darning", self.darning)
        self.repair_button = QPushButton("Repair (F6)")
        self.repair_button.setToolTip("run the repair pipeline; afterwards every edit recomputes it")
        form.addRow("", self.repair_button)

        self.info = QLabel("")
        self.info.setWordWrap(True)
        outer.addWidget(self.info)

        outer.addWidget(QLabel("<b>Layers</b>"))
        self.layer_boxes: dict[str, QCheckBox] = {}
        for name in LAYERS:
            box = QCheckBox(LAYER_TITLES[name])
            box.setChecked(True)
            box.toggled.connect(lambda on, n=name: self.layerToggled.emit(n, on))
            outer.addWidget(box)
            self.layer_boxes[name] = box
        outer.addStretch(1)

        self.show_params(model.params)
        self.show_darning(model.darning)
        model.paramsChanged.connect(self.show_params)
        model.darningChanged.connect(self.show_darning)
        self.darning.currentTextChanged.connect(self._darning_edited)
        self.mode.currentTextChanged.connect(lambda v: self._edit(mode=v))
        self.tracer.currentTextChanged.connect(lambda v: self._edit(tracer=v))
        self.ki_spin.valueChanged.connect(lambda v: self._edit(ki=round(float(v), 4)))
        self.ki_slider.valueChanged.connect(self._slider_moved)
        self.ki_slider.sliderPressed.connect(self._drag_begin)
        self.ki_slider.sliderReleased.connect(self._drag_end)
        self.kt.valueChanged.connect(lambda v: self._edit(kt=float(v)))
        self.step.valueChanged.connect(lambda v: self._edit(step=float(v) if v > 0 else None))
        self.threshold.valueChanged.connect(lambda v: self._edit(threshold=float(v)))
        self.lc.valueChanged.connect(lambda v: self._edit(lc=float(v) if v > 0 else None))

    # ---------------------------------------------------------------- model -> widgets
    def show_params(self, p: FieldParams) -> None:
        widgets = (self.mode, self.tracer, self.ki_slider, self.ki_spin, self.kt, self.step, self.threshold, self.lc)
        for w in widgets:
            w.blockSignals(True)
        try:
            self.mode.setCurrentText(p.mode)
            self.tracer.setCurrentText(p.tracer)
            self.ki_spin.setValue(p.ki)
            self.ki_slider.setValue(int(round(min(p.ki, KI_MAX) / KI_MAX * KI_TICKS)))
            self.kt.setValue(p.kt)
            self.step.setValue(p.step or 0.0)
            self.threshold.setValue(p.threshold)
            self.lc.setValue(p.lc or 0.0)
            self.kt.setEnabled(p.mode == "full")
        finally:
            for w in widgets:
                w.blockSignals(False)

    def show_darning(self, darning: str) -> None:
        self.darning.blockSignals(True)
        self.darning.setCurrentText(darning)
        self.darning.blockSignals(False)

    # ---------------------------------------------------------------- widgets -> model
    def _darning_edited(self, value: str) -> None:
        try:
            self.model.set_darning(value)
        except ValueError as exc:
            self.invalid.emit(str(exc))
            self.show_darning(self.model.darning)

    def _edit(self, **changes) -> None:
        try:
            p = replace(self.model.params, **changes)
        except ValueError as exc:
            self.invalid.emit(str(exc))
            self.show_params(self.model.params)
            return
        self.model.set_params(p, record=self._drag_start is None)

    def _slider_moved(self, value: int) -> None:
        self._edit(ki=round(value / KI_TICKS * KI_MAX, 4))

    def _drag_begin(self) -> None:
        self._drag_start = self.model.params

    def _drag_end(self) -> None:
        start, self._drag_start = self._drag_start, None
        if start is not None and start != self.model.params:
            self.model.push_undo(start)

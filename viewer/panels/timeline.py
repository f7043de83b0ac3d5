"""The Timeline dock: replays a recorded force line step by step.

Play/pause, step back/forward, first/last, speed (steps per second), loop, and a scrub slider.
Frames are the line's recorded steps: nothing is recomputed. A stage list sits on the left: the
field's force lines now; the repair pipeline adds its stages (bridges, hole splits, patches) with
``add_stage``.
"""

from __future__ import annotations

import time

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QHBoxLayout,
    QLabel,
    QSlider,
    QSpinBox,
    QStyle,
    QToolButton,
    QWidget,
)

TICK_MS = 16  # at most ~60 frames a second; faster speeds skip steps


class TimelinePanel(QWidget):
    stageChanged = Signal(str)

    def __init__(self, model, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.timer = QTimer(self)
        self.timer.setTimerType(Qt.PreciseTimer)
        self.timer.timeout.connect(self._tick)
        self._t_last = 0.0
        self._acc = 0.0
        self.frames_shown = 0

        lay = QHBoxLayout(self)
        lay.setContentsMargins(4, 2, 4, 2)
        self.stage = QComboBox()
        self.stage.addItem("Force lines")
        self.stage.setToolTip("what the timeline plays (the repair pipeline adds its stages here)")
        self.stage.currentTextChanged.connect(self.stageChanged)
        lay.addWidget(self.stage)
        st = self.style()

        def button(icon, tip, slot):
            b = QToolButton()
            b.setIcon(st.standardIcon(icon))
            b.setToolTip(tip)
            b.clicked.connect(slot)
            lay.addWidget(b)
            return b

        self.first_button = button(QStyle.SP_MediaSkipBackward, "first step (Home)", self.first)
        self.back_button = button(QStyle.SP_MediaSeekBackward, "step back (,)", self.step_back)
        self.play_button = button(QStyle.SP_MediaPlay, "play / pause (Space)", self.toggle_play)
        self.forward_button = button(QStyle.SP_MediaSeekForward, "step forward (.)", self.step_forward)
        self.last_button = button(QStyle.SP_MediaSkipForward, "last step (End)", self.last)
        self.slider = QSlider(Qt.Horizontal)
        self.slider.setRange(0, 0)
        self.slider.valueChanged.connect(self._scrubbed)
        lay.addWidget(self.slider, 1)
        self.label = QLabel("no line")
        self.label.setMinimumWidth(110)
        lay.addWidget(self.label)
        lay.addWidget(QLabel("speed"))
        self.speed = QSpinBox()
        self.speed.setRange(1, 2000)
        self.speed.setValue(60)
        self.speed.setSuffix(" steps/s")
        lay.addWidget(self.speed)
        self.loop = QCheckBox("loop")
        lay.addWidget(self.loop)

        model.lineChanged.connect(self._line_changed)
        model.frameChanged.connect(self._frame_changed)

    def add_stage(self, name: str) -> None:
        self.stage.addItem(name)

    # ---------------------------------------------------------------- model -> widgets
    def _line_changed(self, line) -> None:
        n = line.steps if line is not None else 0
        self.slider.blockSignals(True)
        self.slider.setRange(0, max(0, n - 1))
        self.slider.blockSignals(False)
        if n == 0:
            self.pause()
            self.label.setText("no line")

    def _frame_changed(self, k: int) -> None:
        self.slider.blockSignals(True)
        self.slider.setValue(k)
        self.slider.blockSignals(False)
        n = self.model.line.steps if self.model.line is not None else 0
        self.label.setText(f"step {k} / {max(0, n - 1)}" if n else "no line")

    def _scrubbed(self, v: int) -> None:
        self.model.set_frame(v)

    # ---------------------------------------------------------------- transport
    @property
    def playing(self) -> bool:
        return self.timer.isActive()

    def play(self) -> None:
        line = self.model.line
        if line is None or line.steps < 2:
            return
        if self.model.frame >= line.steps - 1:
            self.model.set_frame(0)
        self._t_last = time.perf_counter()
        self._acc = 0.0
        self.timer.start(TICK_MS)
        self.play_button.setIcon(self.style().standardIcon(QStyle.SP_MediaPause))

    def pause(self) -> None:
        self.timer.stop()
        self.play_button.setIcon(self.style().standardIcon(QStyle.SP_MediaPlay))

    def toggle_play(self) -> None:
        self.pause() if self.playing else self.play()

    def first(self) -> None:
        self.model.set_frame(0)

    def last(self) -> None:
        if self.model.line is not None:
            self.model.set_frame(self.model.line.steps - 1)

    def step_forward(self) -> None:
        self.pause()
        self.model.set_frame(self.model.frame + 1)

    def step_back(self) -> None:
        self.pause()
        self.model.set_frame(self.model.frame - 1)

    def _tick(self) -> None:
        line = self.model.line
        if line is None:
            self.pause()
            return
        now = time.perf_counter()
        self._acc += (now - self._t_last) * self.speed.value()
        self._t_last = now
        adv = int(self._acc)
        if adv < 1:
            return
        self._acc -= adv
        k = self.model.frame + adv
        last = line.steps - 1
        if k >= last:
            if self.loop.isChecked():
                k = k % (last + 1) if k > last else k
            else:
                k = last
                self.pause()
        self.frames_shown += 1
        self.model.set_frame(k)

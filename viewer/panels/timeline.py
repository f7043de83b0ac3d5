"""The Timeline dock: replays what the algorithms recorded, step by step.

Two modes on one timeline (the list on the left): "Force line" plays the recorded steps of the
force line (selected bridge or traced line); "Repair stages" plays the repair's recorded stages
(input, bridges appear, holes, holes split, then the patches filling hole by hole). Play/pause,
step back/forward, first/last, speed, loop, and a scrub slider work in both. Nothing is
recomputed.
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
STAGE_RATE = 1 / 30  # stages per second per step/s of the speed box (60 steps/s: 2 stages/s)
MODES = ("line", "stages")
MODE_TITLES = ("Force line", "Repair stages")


class TimelinePanel(QWidget):
    playingChanged = Signal(bool)  # playback started (True) or stopped (False)

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
        self.mode = QComboBox()
        self.mode.addItems(MODE_TITLES)
        self.mode.setToolTip("what the timeline plays: the force line's steps, or the repair's stages "
                             "(after Repair, F6)")
        self.mode.model().item(1).setEnabled(False)
        self.mode.currentIndexChanged.connect(lambda i: self.model.set_timeline_mode(MODES[i]))
        lay.addWidget(self.mode)
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
        model.repairChanged.connect(self._repair_changed)
        model.stageChanged.connect(self._stage_changed)
        model.timelineModeChanged.connect(self._mode_changed)

    # ---------------------------------------------------------------- the mode's frames
    @property
    def stages_mode(self) -> bool:
        return self.model.timeline_mode == "stages"

    def count(self) -> int:
        """Frames of what the timeline plays now (steps of the line, or stages)."""
        if self.stages_mode:
            return len(self.model.stages)
        return self.model.line.steps if self.model.line is not None else 0

    def current(self) -> int:
        return self.model.stage if self.stages_mode else self.model.frame

    def goto(self, k: int) -> None:
        (self.model.set_stage if self.stages_mode else self.model.set_frame)(k)

    # ---------------------------------------------------------------- model -> widgets
    def _set_range(self) -> None:
        n = self.count()
        self.slider.blockSignals(True)
        self.slider.setRange(0, max(0, n - 1))
        self.slider.setValue(self.current())
        self.slider.blockSignals(False)
        if n == 0:
            self.pause()
            self.label.setText("no line" if not self.stages_mode else "no repair")

    def _line_changed(self, line) -> None:
        if not self.stages_mode:
            self._set_range()

    def _frame_changed(self, k: int) -> None:
        if self.stages_mode:
            return
        self.slider.blockSignals(True)
        self.slider.setValue(k)
        self.slider.blockSignals(False)
        n = self.count()
        self.label.setText(f"step {k} / {max(0, n - 1)}" if n else "no line")

    def _repair_changed(self, repair) -> None:
        self.mode.model().item(1).setEnabled(repair is not None)
        if self.stages_mode:
            self._set_range()

    def _stage_changed(self, k: int) -> None:
        if not self.stages_mode:
            return
        self.slider.blockSignals(True)
        self.slider.setValue(k)
        self.slider.blockSignals(False)
        st = self.model.stages
        if 0 <= k < len(st):
            self.label.setText(f"stage {k + 1} / {len(st)}: {st[k].name}")
            self.label.setToolTip(st[k].description)

    def _mode_changed(self, mode: str) -> None:
        self.pause()
        self.mode.blockSignals(True)
        self.mode.setCurrentIndex(MODES.index(mode))
        self.mode.blockSignals(False)
        self._set_range()
        if mode == "stages":
            self._stage_changed(self.model.stage)
        else:
            self._frame_changed(self.model.frame)

    def _scrubbed(self, v: int) -> None:
        self.goto(v)

    # ---------------------------------------------------------------- transport
    @property
    def playing(self) -> bool:
        return self.timer.isActive()

    def play(self) -> None:
        n = self.count()
        if n < 2:
            return
        if self.current() >= n - 1:
            self.goto(0)
        self._t_last = time.perf_counter()
        self._acc = 0.0
        was = self.timer.isActive()
        self.timer.start(TICK_MS)
        self.play_button.setIcon(self.style().standardIcon(QStyle.SP_MediaPause))
        if not was:
            self.playingChanged.emit(True)

    def pause(self) -> None:
        was = self.timer.isActive()
        self.timer.stop()
        self.play_button.setIcon(self.style().standardIcon(QStyle.SP_MediaPlay))
        if was:
            self.playingChanged.emit(False)

    def toggle_play(self) -> None:
        self.pause() if self.playing else self.play()

    def first(self) -> None:
        self.goto(0)

    def last(self) -> None:
        if self.count():
            self.goto(self.count() - 1)

    def step_forward(self) -> None:
        self.pause()
        self.goto(self.current() + 1)

    def step_back(self) -> None:
        self.pause()
        self.goto(self.current() - 1)

    def _tick(self) -> None:
        n = self.count()
        if n == 0:
            self.pause()
            return
        now = time.perf_counter()
        rate = self.speed.value() * (STAGE_RATE if self.stages_mode else 1.0)
        self._acc += (now - self._t_last) * rate
        self._t_last = now
        adv = int(self._acc)
        if adv < 1:
            return
        self._acc -= adv
        k = self.current() + adv
        last = n - 1
        if k >= last:
            if self.loop.isChecked():
                k = k % (last + 1) if k > last else k
            else:
                k = last
                self.pause()
        self.frames_shown += 1
        self.goto(k)

"""The explorer's one mutable state (napari style: one model, many views).

Views connect to the signals in their ``__init__`` and redraw from the model; widgets write
through the model's setters. Nothing here draws or computes: the worker computes, the scene
view draws.

State: the input (an ``Icadm`` and where it came from), the field parameters and the darning
method (with an undo/redo stack of edits), the latest result of the field (a ``BridgeSet``), the
latest repair (a ``RepairResult``, with its recorded stages), the selected bridge, and the
timeline: the force line and its current step, or the repair's stages and the current stage.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from PySide6.QtCore import QObject, Signal

from algorithms.boundary import LoopFrame, loop_frames
from algorithms.mesh import Icadm
from algorithms.params import FieldParams
from algorithms.records import ForceLine
from algorithms.repair import DARNING, RepairParams

from .stages import StageFrame, stage_frames

DEFAULT_DARNING = RepairParams().darning


@dataclass(frozen=True)
class Source:
    """Where the input came from (for titles, recent files and sessions)."""

    path: str
    points: str | None = None
    demo: str | None = None

    def label(self) -> str:
        return f"demo {self.demo}" if self.demo else self.path


class ExplorerModel(QObject):
    inputChanged = Signal()  # a new Icadm (and source); results are cleared
    paramsChanged = Signal(object)  # FieldParams
    resultChanged = Signal(object)  # BridgeSet or None
    selectionChanged = Signal(int)  # candidate index, -1 = none
    lineChanged = Signal(object)  # the ForceLine on the timeline (or None)
    frameChanged = Signal(int)  # step index of the line on the timeline
    undoStateChanged = Signal(bool, bool)  # can undo, can redo
    darningChanged = Signal(str)
    repairChanged = Signal(object)  # RepairResult or None
    stageChanged = Signal(int)  # index into ``stages``
    timelineModeChanged = Signal(str)  # "line" or "stages"

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.icadm: Icadm | None = None
        self.source: Source | None = None
        self.frames: list[LoopFrame] = []
        self.params = FieldParams()
        self.result = None
        self.selection = -1
        self.line: ForceLine | None = None
        self.line_label = ""
        self.frame = 0
        self.darning = DEFAULT_DARNING
        self.repair = None  # RepairResult for (icadm, params, darning) or None
        self.repair_wanted = False  # the user asked for a repair: edits recompute it
        self.stages: list[StageFrame] = []
        self.stage = 0
        self.timeline_mode = "line"
        self._undo: list[tuple[FieldParams, str]] = []
        self._redo: list[tuple[FieldParams, str]] = []

    # ---------------------------------------------------------------- input
    def set_input(self, icadm: Icadm, source: Source) -> None:
        self.icadm = icadm
        self.source = source
        self.frames = loop_frames(icadm.mesh, charge=self.params.charge)
        self.result = None
        self.selection = -1
        self.line = None
        self.frame = 0
        self.repair_wanted = False
        self.inputChanged.emit()
        self.resultChanged.emit(None)
        self.set_repair(None)
        self.lineChanged.emit(None)

    # ---------------------------------------------------------------- parameters
    @property
    def repair_params(self) -> RepairParams:
        return RepairParams(field=self.params, darning=self.darning)

    def _state(self) -> tuple[FieldParams, str]:
        return self.params, self.darning

    def _apply(self, state: tuple[FieldParams, str]) -> None:
        params, darning = state
        if darning != self.darning:
            self.darning = darning
            self.set_repair(None)
            self.darningChanged.emit(darning)
        if params != self.params:
            self.params = params
            self.set_repair(None)
            self.paramsChanged.emit(params)

    def _record(self, previous: tuple[FieldParams, str]) -> None:
        self._undo.append(previous)
        self._redo.clear()

    def set_params(self, params: FieldParams, *, record: bool = True) -> None:
        """New parameters (a recorded edit can be undone)."""
        if params == self.params:
            return
        if record:
            self._record(self._state())
        self._apply((params, self.darning))
        self.undoStateChanged.emit(self.can_undo, self.can_redo)

    def set_darning(self, darning: str, *, record: bool = True) -> None:
        """The darning method of the repair (one of algorithms.repair.DARNING)."""
        if darning not in DARNING:
            raise ValueError(f"parameter darning={darning!r}: must be one of {', '.join(DARNING)}")
        if darning == self.darning:
            return
        if record:
            self._record(self._state())
        self._apply((self.params, darning))
        self.undoStateChanged.emit(self.can_undo, self.can_redo)

    def edit(self, **changes) -> None:
        """Change some parameters (raises ValueError naming a bad parameter)."""
        self.set_params(replace(self.params, **changes))

    def push_undo(self, previous: FieldParams) -> None:
        """Record an edit made of unrecorded steps (a slider drag) as one undo step."""
        self._record((previous, self.darning))
        self.undoStateChanged.emit(self.can_undo, self.can_redo)

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)

    def undo(self) -> None:
        if not self._undo:
            return
        self._redo.append(self._state())
        self._apply(self._undo.pop())
        self.undoStateChanged.emit(self.can_undo, self.can_redo)

    def redo(self) -> None:
        if not self._redo:
            return
        self._undo.append(self._state())
        self._apply(self._redo.pop())
        self.undoStateChanged.emit(self.can_undo, self.can_redo)

    # ---------------------------------------------------------------- results
    def set_result(self, result) -> None:
        """A BridgeSet computed for the current input and parameters (None clears)."""
        self.result = result
        self.resultChanged.emit(result)
        cands = self.candidates()
        keep = self.selection if 0 <= self.selection < len(cands) else -1
        if keep < 0 and cands:
            keep = max(range(len(cands)), key=lambda i: (cands[i].line.arrived, cands[i].quality))
        self.select(keep, force=True)

    def set_repair(self, repair) -> None:
        """A RepairResult for the current input and parameters (None clears it and its stages)."""
        if repair is None and self.repair is None:
            return
        self.repair = repair
        self.stages = stage_frames(repair) if repair is not None else []
        self.stage = len(self.stages) - 1 if self.stages else 0
        self.repairChanged.emit(repair)
        if not self.stages and self.timeline_mode == "stages":
            self.set_timeline_mode("line")
        elif self.timeline_mode == "stages":
            self.stageChanged.emit(self.stage)

    def set_timeline_mode(self, mode: str) -> None:
        """What the timeline plays: "line" (the force line) or "stages" (the repair's stages)."""
        if mode not in ("line", "stages"):
            raise ValueError(f"timeline mode {mode!r}: must be 'line' or 'stages'")
        if mode == "stages" and not self.stages:
            mode = "line"
        if mode == self.timeline_mode:
            return
        self.timeline_mode = mode
        self.timelineModeChanged.emit(mode)
        if mode == "stages":
            self.stageChanged.emit(self.stage)

    def set_stage(self, k: int) -> None:
        n = len(self.stages)
        self.stage = max(0, min(int(k), n - 1)) if n else 0
        self.stageChanged.emit(self.stage)

    def candidates(self) -> tuple:
        return tuple(self.result.candidates) if self.result is not None else ()

    def select(self, index: int, *, force: bool = False) -> None:
        """Select a candidate bridge (its force line goes on the timeline)."""
        cands = self.candidates()
        index = index if 0 <= index < len(cands) else -1
        if index == self.selection and not force:
            return
        self.selection = index
        self.selectionChanged.emit(index)
        if index >= 0:
            line = cands[index].line
            if self.line is not None and self.line_label == f"bridge {index}" and _same_line(self.line, line):
                self.line = line  # a recompute that did not move the line (k_i): nothing to redraw
                return
            self.set_line(line, label=f"bridge {index}")

    def set_line(self, line: ForceLine | None, *, label: str = "", frame: int | None = None) -> None:
        self.line = line
        self.line_label = label
        self.lineChanged.emit(line)
        n = line.steps if line is not None else 0
        self.set_frame(n - 1 if frame is None else frame)

    def set_frame(self, frame: int) -> None:
        n = self.line.steps if self.line is not None else 0
        frame = max(0, min(int(frame), n - 1)) if n else 0
        self.frame = frame
        self.frameChanged.emit(frame)

    # ---------------------------------------------------------------- helpers
    def loop_of_vertex(self, vertex: int) -> tuple[int, int]:
        """(loop number, index along the loop) of a boundary vertex, (-1, -1) if not on a loop."""
        for li, f in enumerate(self.frames):
            hit = (f.vertices == vertex).nonzero()[0]
            if len(hit):
                return li, int(hit[0])
        return -1, -1


def _same_line(a: ForceLine, b: ForceLine) -> bool:
    """The same recorded steps (points, normals, forces) and ending."""
    return (a is b) or (a.status == b.status and a.steps == b.steps and np.array_equal(a.points, b.points)
                        and np.array_equal(a.normals, b.normals) and np.array_equal(a.forces, b.forces))

"""The explorer's one mutable state (napari style: one model, many views).

Views connect to the signals in their ``__init__`` and redraw from the model; widgets write
through the model's setters. Nothing here draws or computes: the worker computes, the scene
view draws.

State: the input (an ``Icadm`` and where it came from), the field parameters (with an undo/redo
stack of edits), the latest result of the field (a ``BridgeSet``), the selected bridge, the
force line on the timeline and its current frame.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from PySide6.QtCore import QObject, Signal

from algorithms.boundary import LoopFrame, loop_frames
from algorithms.mesh import Icadm
from algorithms.params import FieldParams
from algorithms.records import ForceLine


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
        self._undo: list[FieldParams] = []
        self._redo: list[FieldParams] = []

    # ---------------------------------------------------------------- input
    def set_input(self, icadm: Icadm, source: Source) -> None:
        self.icadm = icadm
        self.source = source
        self.frames = loop_frames(icadm.mesh, charge=self.params.charge)
        self.result = None
        self.selection = -1
        self.line = None
        self.frame = 0
        self.inputChanged.emit()
        self.resultChanged.emit(None)
        self.lineChanged.emit(None)

    # ---------------------------------------------------------------- parameters
    def set_params(self, params: FieldParams, *, record: bool = True) -> None:
        """New parameters (a recorded edit can be undone)."""
        if params == self.params:
            return
        if record:
            self._undo.append(self.params)
            self._redo.clear()
        self.params = params
        self.paramsChanged.emit(params)
        self.undoStateChanged.emit(self.can_undo, self.can_redo)

    def edit(self, **changes) -> None:
        """Change some parameters (raises ValueError naming a bad parameter)."""
        self.set_params(replace(self.params, **changes))

    def push_undo(self, previous: FieldParams) -> None:
        """Record an edit made of unrecorded steps (a slider drag) as one undo step."""
        self._undo.append(previous)
        self._redo.clear()
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
        self._redo.append(self.params)
        self.params = self._undo.pop()
        self.paramsChanged.emit(self.params)
        self.undoStateChanged.emit(self.can_undo, self.can_redo)

    def redo(self) -> None:
        if not self._redo:
            return
        self._undo.append(self.params)
        self.params = self._redo.pop()
        self.paramsChanged.emit(self.params)
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
            self.set_line(cands[index].line, label=f"bridge {index}")

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

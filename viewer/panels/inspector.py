"""The Inspector dock: what is under the cursor of the timeline and what is selected.

For the force line on the timeline: the current step's point, normal, force and tension |H n|,
how the line ended; for a selected bridge: its factors (q_T, q1, q2, q12, q3, q4, Q, eqs. 2-10)
and its endpoints; for a clicked boundary point: its loop, Ω there; once a repair exists, its
summary (class, bridges by kind, rejected candidates, holes split and darned, new faces) and the
stage on the timeline.
"""

from __future__ import annotations

import time

import numpy as np
from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QTextBrowser, QVBoxLayout, QWidget

from algorithms.bridge_graph import BRIDGE_KINDS


def _v(a) -> str:
    a = np.asarray(a, dtype=float)
    return "(" + ", ".join(f"{x:.4g}" for x in a) + ")"


class InspectorPanel(QWidget):
    def __init__(self, model, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.text = QTextBrowser()
        lay = QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addWidget(self.text)
        self.picked: dict | None = None  # the last clicked boundary point
        self._last = 0.0
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.timeout.connect(self.refresh)
        model.frameChanged.connect(self.refresh)
        model.selectionChanged.connect(self.refresh)
        model.resultChanged.connect(self.refresh)
        model.repairChanged.connect(self.refresh)
        model.stageChanged.connect(self.refresh)
        model.timelineModeChanged.connect(self.refresh)
        model.inputChanged.connect(self._clear_pick)
        self.refresh()

    def _clear_pick(self) -> None:
        self.picked = None
        self.refresh()

    def set_picked(self, info: dict | None) -> None:
        self.picked = info
        self._last = 0.0
        self.refresh()

    def html(self) -> str:
        m = self.model
        parts = []
        if self.picked:
            p = self.picked
            om = p.get("omega")
            parts.append(f"<h4>Boundary point {p['vertex']}</h4>loop {p['loop']}, index {p['index']}<br>"
                         f"point {_v(p['point'])}<br>Ω = {'–' if om is None else f'{om:.4g}'}")
        line = m.line
        if line is not None and line.steps:
            k = m.frame
            parts.append(f"<h4>Force line: {m.line_label}</h4>"
                         f"status <b>{line.status}</b>, {line.steps} steps, length {line.length:.4g}, "
                         f"quality (mean tension) {line.quality:.4g}<br>"
                         f"start vertex {line.start_vertex} (island {line.start_island})"
                         + (f", end vertex {line.end_vertex} (island {line.end_island})" if line.arrived else "")
                         + f"<br><b>step {k}</b>: X = {_v(line.points[k])}<br>normal n = {_v(line.normals[k])}"
                         f"<br>force H n = {_v(line.forces[k])}<br>tension |H n| = {float(line.tensions[k]):.4g}")
        cands = m.candidates()
        if 0 <= m.selection < len(cands):
            c = cands[m.selection]
            rows = [("quality", c.quality), ("start loop", c.start_loop), ("start index", c.start_index)]
            if c.factors is not None:
                f = c.factors
                rows += [("q_T (2)", f.qT), ("q1 (3)", f.q1), ("q2 (4)", f.q2), ("q12 (8)", f.q12),
                         ("q3 (5)", f.q3), ("q4 (7)", f.q4), ("Q (9)-(10)", f.Q)]
            body = "".join(f"<tr><td>{k}</td><td align=right>{v:.4g}</td></tr>" if isinstance(v, float)
                           else f"<tr><td>{k}</td><td align=right>{v}</td></tr>" for k, v in rows)
            parts.append(f"<h4>Bridge {m.selection}</h4><table>{body}</table>")
        r = m.repair
        if r is not None:
            darned = sum(h.split_by < 0 for h in r.holes)
            split = sum(h.split_by >= 0 for h in r.holes)
            kinds = ", ".join(f"{sum(b.kind == k for b in r.bridges)} {k}" for k in BRIDGE_KINDS)
            stage = ""
            if m.timeline_mode == "stages" and 0 <= m.stage < len(m.stages):
                st = m.stages[m.stage]
                stage = f"<br><b>stage {m.stage + 1} / {len(m.stages)}: {st.name}</b> — {st.description}"
            parts.append(f"<h4>Repair ({r.class_found})</h4>{len(r.bridges)} bridges ({kinds}), "
                         f"{len(r.rejected)} candidates rejected; {split} holes split, {darned} darned with "
                         f"{r.params.darning}; {len(r.new_faces)} new faces; "
                         f"{sum(r.timings.get(k, 0.0) for k in ('total',)) * 1000:.0f} ms{stage}")
        if not parts:
            parts.append("Click a boundary point in the 3D view to trace a force line from it; "
                         "select a bridge (3D view or table) to see its factors.")
        return "".join(parts)

    def refresh(self, *_):
        """Rewrite the text (at most ~8 times a second while the timeline plays)."""
        now = time.perf_counter()
        if now - self._last < 0.12:
            if not self._timer.isActive():
                self._timer.start(130)
            return
        self._last = now
        self.text.setHtml(self.html())


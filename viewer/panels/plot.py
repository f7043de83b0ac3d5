"""The Plot dock: a matplotlib figure (tension along the force line on the timeline, with the
current step marked); ``histogram`` serves later workspaces (min-angle histograms of meshes)."""

from __future__ import annotations

import time

import numpy as np
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.figure import Figure
from PySide6.QtWidgets import QVBoxLayout, QWidget

MARKER_PERIOD = 0.05  # seconds between marker moves while playing (blitted: cheap)


class PlotPanel(QWidget):
    def __init__(self, model, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.figure = Figure(figsize=(4, 2.2), tight_layout=True)
        self.canvas = FigureCanvasQTAgg(self.figure)
        self.ax = self.figure.add_subplot(111)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addWidget(self.canvas)
        self._marker = None
        self._background = None
        self._last_marker = 0.0
        self.canvas.mpl_connect("draw_event", self._drawn)
        model.lineChanged.connect(self.plot_line)
        model.frameChanged.connect(self.mark)
        self.plot_line(None)

    def plot_line(self, line) -> None:
        ax = self.ax
        ax.clear()
        self._marker = None
        self._background = None
        if line is None or line.steps == 0:
            ax.set_title("tension along the force line", fontsize=9)
            ax.text(0.5, 0.5, "no line", ha="center", va="center", transform=ax.transAxes)
        else:
            ax.plot(np.arange(line.steps), line.tensions, color="#1f77b4", lw=1.5)
            ax.set_xlabel("step", fontsize=8)
            ax.set_ylabel("|H n|", fontsize=8)
            ax.set_title(f"tension along the line ({line.status})", fontsize=9)
            ax.tick_params(labelsize=7)
            self._marker = ax.axvline(self.model.frame, color="#d62728", lw=1, animated=True)
        self.canvas.draw_idle()

    def _drawn(self, _event) -> None:
        """After a full draw: keep the background (without the marker) for blitting."""
        self._background = self.canvas.copy_from_bbox(self.ax.bbox)
        if self._marker is not None:
            self.ax.draw_artist(self._marker)
            self.canvas.blit(self.ax.bbox)

    def mark(self, k: int) -> None:
        """Move the current-step marker: blitted over the kept background (no full redraw)."""
        if self._marker is None:
            return
        self._marker.set_xdata([k, k])
        if not self.isVisible():
            return
        if self._background is None:
            self.canvas.draw_idle()
            return
        now = time.perf_counter()
        line = self.model.line
        last = line is not None and k >= line.steps - 1
        if now - self._last_marker < MARKER_PERIOD and not last and k != 0:
            return
        self._last_marker = now
        self.canvas.restore_region(self._background)
        self.ax.draw_artist(self._marker)
        self.canvas.blit(self.ax.bbox)

    def histogram(self, values, *, bins=36, title: str = "", xlabel: str = "", marks=()) -> None:
        """A histogram of values (e.g. minimum angles, degrees) with vertical marks."""
        ax = self.ax
        ax.clear()
        self._marker = None
        self._background = None
        v = np.asarray(values, dtype=float)
        ax.hist(v[np.isfinite(v)], bins=bins, color="#4c78a8", edgecolor="white")
        for m in marks:
            ax.axvline(m, color="#d62728", lw=1, ls="--")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.tick_params(labelsize=7)
        self.canvas.draw_idle()

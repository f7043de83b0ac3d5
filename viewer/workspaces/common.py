"""Shared pieces of the explorer workspaces: a latest-wins background job runner and the
embedded min-angle histogram (matplotlib in Qt).

Rendering stays on the GUI thread: a job computes numpy data in a pool thread and its result
comes back through a queued Qt signal.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable
from typing import Any

import numpy as np
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.figure import Figure
from numpy.typing import NDArray
from PySide6.QtCore import QObject, QRunnable, QThreadPool, QTimer, Signal

from algorithms.metrics import AngleStats, angle_histogram, angle_stats


class _Relay(QObject):
    """Lives in the GUI thread; the pool thread emits on it (queued delivery)."""

    done = Signal(int, bool, object)


class _Job(QRunnable):
    def __init__(self, gen: int, fn: Callable[..., Any], args: tuple, relay: _Relay) -> None:
        super().__init__()
        self.setAutoDelete(True)
        self.gen, self.fn, self.args, self.relay = gen, fn, args, relay

    def run(self) -> None:
        ok = False
        try:
            value = self.fn(*self.args)
            ok = True
        except Exception as exc:  # reported to the user, never raised in the pool thread
            value = f"{type(exc).__name__}: {exc}"
            traceback.print_exc()
        try:
            self.relay.done.emit(self.gen, ok, value)
        except RuntimeError:  # the relay was deleted (workspace closed): nothing to tell
            pass


class JobRunner(QObject):
    """Runs one job at a time off the GUI thread; the latest request wins.

    ``submit(fn, *args)`` asks for a new computation. If a job is running it is not interrupted
    (the algorithms have no cancel hook) but its result is dropped when it returns, and the
    latest request starts then. ``cancel()`` drops the running job's result and any pending
    request. ``shutdown()`` waits for the pool thread (call it before closing the widget).
    """

    finished = Signal(object)  # the result of the latest request
    failed = Signal(str)  # the error text of the latest request
    busy_changed = Signal(bool)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self._relay = _Relay(self)
        self._relay.done.connect(self._on_done)
        self._gen = 0  # id of the latest request; results of older ones are stale
        self._running: int | None = None  # id of the job in the pool thread
        self._pending: tuple[int, Callable[..., Any], tuple] | None = None
        self._closed = False
        self.dropped = 0  # stale results thrown away (for tests and the status line)

    @property
    def busy(self) -> bool:
        """A result is awaited (a cancelled job may still occupy the thread: see ``running``)."""
        return self._pending is not None or (self._running is not None and self._running == self._gen)

    @property
    def running(self) -> bool:
        """The pool thread is computing (possibly a job whose result will be dropped)."""
        return self._running is not None

    def submit(self, fn: Callable[..., Any], *args: Any) -> int:
        if self._closed:
            return self._gen
        was_busy = self.busy
        self._gen += 1
        self._pending = (self._gen, fn, args)
        if self._running is None:
            self._start_pending()
        if not was_busy:
            self.busy_changed.emit(True)
        return self._gen

    def cancel(self) -> None:
        """Forget the pending request and drop the running job's result when it returns."""
        was_busy = self.busy
        self._gen += 1
        self._pending = None
        if was_busy:
            self.busy_changed.emit(False)

    def shutdown(self, timeout_ms: int = 60_000) -> None:
        self._closed = True
        self._pending = None
        self._gen += 1
        self._pool.waitForDone(timeout_ms)
        self._running = None

    def _start_pending(self) -> None:
        assert self._pending is not None
        gen, fn, args = self._pending
        self._pending = None
        self._running = gen
        self._pool.start(_Job(gen, fn, args, self._relay))

    def _on_done(self, gen: int, ok: bool, value: object) -> None:
        self._running = None
        if self._closed:
            return
        if self._pending is not None:  # a newer request is waiting: this result is stale
            self.dropped += 1
            self._start_pending()
            return
        if gen != self._gen:  # cancelled
            self.dropped += 1
            return
        self.busy_changed.emit(False)
        if ok:
            self.finished.emit(value)
        else:
            self.failed.emit(str(value))


def debounce(parent: QObject, ms: int, slot: Callable[[], None]) -> QTimer:
    """A single-shot timer: ``timer.start()`` on every edit, ``slot`` runs once they stop."""
    t = QTimer(parent)
    t.setSingleShot(True)
    t.setInterval(ms)
    t.timeout.connect(slot)
    return t


def stats_text(s: AngleStats, *, label: str = "") -> str:
    head = f"{label}: " if label else ""
    if not s.count:
        return f"{head}no triangles"
    return (f"{head}{s.count} triangles · min {s.min:.2f}° · 1st pct {s.p01:.2f}° · median {s.median:.2f}° · "
            f"below 20° {100 * s.below_20:.2f} % · below 30° {100 * s.below_30:.2f} %")


class AngleHistogram(FigureCanvasQTAgg):
    """Min-angle histogram: a main series as bars, an optional second series as an outline,
    a threshold line, and the statistics in the title area.

    ``counts`` and ``overlay_counts`` hold what is plotted (for tests and exports)."""

    def __init__(self, parent=None) -> None:
        self.figure = Figure(figsize=(5, 2.4), dpi=90, layout="constrained")
        super().__init__(self.figure)
        self.setParent(parent)
        self.ax = self.figure.add_subplot(111)
        self.edges: NDArray[np.float64] = np.zeros(0)
        self.counts: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
        self.overlay_counts: NDArray[np.int64] | None = None
        self.stats: AngleStats | None = None
        self.setMinimumHeight(160)

    def show_angles(self, angles: NDArray[np.float64], *, label: str = "after",
                    overlay: NDArray[np.float64] | None = None, overlay_label: str = "before",
                    threshold: float | None = None, show_overlay: bool = True,
                    colour: str = "#4c8cbf", overlay_colour: str = "#d62728", share: bool = False) -> None:
        """Plot the histogram of ``angles`` (degrees); ``share``: heights in % of each series'
        triangles (so that series of very different sizes compare), else counts."""
        ax = self.ax
        ax.clear()
        edges, counts = angle_histogram(np.asarray(angles, dtype=np.float64))
        self.edges, self.counts = edges, counts
        self.stats = angle_stats(angles)
        width = np.diff(edges)

        def height(c: NDArray[np.int64]) -> NDArray[np.float64]:
            return 100.0 * c / max(int(c.sum()), 1) if share else c.astype(np.float64)

        ax.bar(edges[:-1], height(counts), width=width, align="edge", color=colour, edgecolor="#333333",
               linewidth=0.5, label=f"{label} ({len(angles)})", alpha=0.85)
        self.overlay_counts = None
        if overlay is not None and show_overlay:
            _, oc = angle_histogram(np.asarray(overlay, dtype=np.float64))
            self.overlay_counts = oc
            ax.stairs(height(oc), edges, color=overlay_colour, linewidth=1.5, label=f"{overlay_label} ({len(overlay)})")
        if threshold is not None:
            ax.axvline(threshold, color="#2ca02c", linestyle="--", linewidth=1.2, label=f"threshold {threshold:g}°")
        for a, c in ((20, "#999999"), (30, "#666666")):
            ax.axvline(a, color=c, linestyle=":", linewidth=0.8)
        ax.set_xlim(0, 60)
        ax.set_xlabel("triangle min angle (°)")
        ax.set_ylabel("% of triangles" if share else "triangles")
        ax.legend(loc="upper left", fontsize=7, frameon=False)
        s = self.stats
        if s.count:
            ax.set_title(f"min {s.min:.1f}°  p1 {s.p01:.1f}°  median {s.median:.1f}°  "
                         f"<20° {100 * s.below_20:.1f} %  <30° {100 * s.below_30:.1f} %", fontsize=8)
        self.draw_idle()

    def clear_plot(self) -> None:
        self.ax.clear()
        self.counts = np.zeros(0, dtype=np.int64)
        self.overlay_counts = None
        self.stats = None
        self.draw_idle()

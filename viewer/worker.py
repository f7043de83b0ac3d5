"""Running algorithm calls off the GUI thread, with progress, cancel and stale-result dropping.

A job is a callable ``fn(progress=..., cancel=...)``: ``progress(fraction)`` (or
``progress(done, total)``, or ``progress(fraction, message)``) reports how far it is,
``cancel()`` returns True once the job should stop (the algorithm then raises
:class:`algorithms.records.Cancelled`). Jobs run in QThreads and report through Qt signals,
which Qt queues to the GUI thread: no VTK call ever happens here.

Jobs have a *kind* ("field", "trace", ...). Submitting a job of a kind cancels the running job of
that kind; a job's result lands only if it is still the newest of its kind (stale results are
dropped). :meth:`Worker.schedule` debounces: a burst of edits starts one job.
"""

from __future__ import annotations

import time
import traceback
from collections.abc import Callable

from PySide6.QtCore import QObject, QThread, QTimer, Signal

from algorithms.records import Cancelled


class _Job(QThread):
    progressed = Signal(int, float)
    succeeded = Signal(int, object, float)
    failed = Signal(int, str)
    stopped = Signal(int)

    def __init__(self, job_id: int, fn: Callable, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.job_id = job_id
        self.fn = fn
        self.cancel_requested = False
        self._last_progress = 0.0

    def _progress(self, *args) -> None:
        if len(args) >= 2 and isinstance(args[1], (int, float)) and args[1]:  # (done, total)
            frac = float(args[0]) / float(args[1])
        elif args:
            frac = float(args[0])
        else:
            return
        now = time.perf_counter()
        if now - self._last_progress > 0.03 or frac >= 1.0:  # don't flood the event loop
            self._last_progress = now
            self.progressed.emit(self.job_id, frac)

    def _cancel(self) -> bool:
        return self.cancel_requested or self.isInterruptionRequested()

    def run(self) -> None:  # runs in the thread
        t0 = time.perf_counter()
        try:
            result = self.fn(progress=self._progress, cancel=self._cancel)
        except Cancelled:
            self.stopped.emit(self.job_id)
            return
        except Exception as exc:  # reported in the window; the window keeps working
            msg = f"{type(exc).__name__}: {exc}"
            tb = traceback.format_exc(limit=6)
            self.failed.emit(self.job_id, f"{msg}\n\n{tb}")
            return
        if self._cancel():
            self.stopped.emit(self.job_id)
        else:
            self.succeeded.emit(self.job_id, result, time.perf_counter() - t0)


class Worker(QObject):
    """Runs jobs by kind; emits (kind, ...) signals on the GUI thread."""

    started = Signal(str)
    progress = Signal(str, float)
    finished = Signal(str, object, float)  # kind, result, seconds
    failed = Signal(str, str)  # kind, message
    cancelled = Signal(str)
    busyChanged = Signal(bool)

    def __init__(self, parent: QObject | None = None, *, debounce_ms: int = 40) -> None:
        super().__init__(parent)
        self._next_id = 0
        self._latest: dict[str, int] = {}  # kind -> id of the newest job
        self._kind: dict[int, str] = {}
        self._threads: dict[int, _Job] = {}
        self._pending: dict[str, Callable] = {}
        self._timers: dict[str, QTimer] = {}
        self.debounce_ms = debounce_ms

    # ---------------------------------------------------------------- submit
    def submit(self, kind: str, fn: Callable) -> int:
        """Start fn now in a new thread (cancelling the running job of the same kind)."""
        self._pending.pop(kind, None)
        self.cancel(kind)
        self._next_id += 1
        jid = self._next_id
        job = _Job(jid, fn)
        job.progressed.connect(self._on_progress)
        job.succeeded.connect(self._on_success)
        job.failed.connect(self._on_failed)
        job.stopped.connect(self._on_stopped)
        job.finished.connect(lambda j=job: self._reap(j))
        self._latest[kind] = jid
        self._kind[jid] = kind
        self._threads[jid] = job
        was_busy = self.busy
        job.start()
        self.started.emit(kind)
        if not was_busy:
            self.busyChanged.emit(True)
        return jid

    def schedule(self, kind: str, fn: Callable, delay_ms: int | None = None) -> None:
        """Debounced submit: the last fn scheduled within the delay runs."""
        self._pending[kind] = fn
        timer = self._timers.get(kind)
        if timer is None:
            timer = QTimer(self)
            timer.setSingleShot(True)
            timer.timeout.connect(lambda k=kind: self._fire(k))
            self._timers[kind] = timer
        timer.start(self.debounce_ms if delay_ms is None else delay_ms)

    def _fire(self, kind: str) -> None:
        fn = self._pending.pop(kind, None)
        if fn is not None:
            self.submit(kind, fn)

    # ---------------------------------------------------------------- cancel
    def cancel(self, kind: str | None = None) -> None:
        """Ask running jobs (of one kind, or all) to stop; their results will be dropped."""
        for jid, job in list(self._threads.items()):
            if kind is None or self._kind.get(jid) == kind:
                job.cancel_requested = True
                job.requestInterruption()
                if self._latest.get(self._kind.get(jid, "")) == jid:
                    self._latest.pop(self._kind[jid], None)
                    self.cancelled.emit(self._kind[jid])
        if kind is None:
            self._pending.clear()
            for t in self._timers.values():
                t.stop()

    @property
    def busy(self) -> bool:
        return any(j.isRunning() for j in self._threads.values())

    def running(self) -> int:
        return sum(1 for j in self._threads.values() if j.isRunning())

    def shutdown(self, timeout_ms: int = 10000) -> bool:
        """Cancel everything and wait for the threads to end (call before closing the window)."""
        self.cancel()
        ok = True
        for job in list(self._threads.values()):
            ok &= bool(job.wait(timeout_ms))
        return ok

    def wait_idle(self, timeout_ms: int = 10000) -> bool:
        deadline = time.perf_counter() + timeout_ms / 1000
        for job in list(self._threads.values()):
            left = max(1, int((deadline - time.perf_counter()) * 1000))
            if not job.wait(left):
                return False
        return True

    # ---------------------------------------------------------------- slots (GUI thread)
    def _current(self, jid: int) -> str | None:
        kind = self._kind.get(jid)
        return kind if kind is not None and self._latest.get(kind) == jid else None

    def _on_progress(self, jid: int, frac: float) -> None:
        kind = self._current(jid)
        if kind:
            self.progress.emit(kind, frac)

    def _on_success(self, jid: int, result: object, seconds: float) -> None:
        kind = self._current(jid)
        if kind:  # a stale job's result is dropped here
            self._latest.pop(kind, None)
            self.finished.emit(kind, result, seconds)

    def _on_failed(self, jid: int, message: str) -> None:
        kind = self._current(jid)
        if kind:
            self._latest.pop(kind, None)
            self.failed.emit(kind, message)

    def _on_stopped(self, jid: int) -> None:
        kind = self._current(jid)
        if kind:
            self._latest.pop(kind, None)
            self.cancelled.emit(kind)

    def _reap(self, job: _Job) -> None:
        self._threads.pop(job.job_id, None)
        self._kind.pop(job.job_id, None)
        # QThread.finished is emitted just before the thread ends: deleting it before then aborts the
        # process ("QThread: Destroyed while thread is still running"; seen once in ~15 runs of the
        # window tests, in the teardown's DeferredDelete pass). Wait the moment until it has ended.
        if QThread.currentThread() is not job:
            job.wait(5000)
        job.deleteLater()
        if not self.busy:
            self.busyChanged.emit(False)

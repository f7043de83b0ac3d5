"""Algorithm calls in worker processes, so the GUI thread never waits for the GIL.

The field's numba kernels hold the GIL while they run (hundreds of milliseconds in full mode):
in a worker *thread* they would freeze the GUI thread that long. Here they run in a small pool
of spawned processes; a QThread of :mod:`viewer.worker` waits for the answer, relays progress
and cancel through shared memory (one slot per running call), and the GUI stays free.

Only picklable calls go here: module-level functions and plain data (an Icadm, FieldParams...).
"""

from __future__ import annotations

import multiprocessing as mp
import threading
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from concurrent.futures.process import BrokenProcessPool

from algorithms.records import Cancelled

SLOTS = 64  # calls in flight at most (a slot is reused after SLOTS calls)

_flags = None  # in a worker: shared cancel flags, one per slot
_progress = None  # in a worker: shared progress fractions, one per slot


def _init(flags, progress) -> None:
    import signal

    global _flags, _progress
    _flags, _progress = flags, progress
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl+C in the terminal is for the window, not the workers


def _run(slot: int, fn: Callable, args: tuple, control: bool):
    """In the worker: call fn(*args[, progress=, cancel=]) with this slot's flag and progress."""
    if not control:
        return fn(*args)

    def cancel() -> bool:
        return bool(_flags[slot])

    def progress(*a) -> None:
        if len(a) >= 2 and isinstance(a[1], (int, float)) and a[1]:
            _progress[slot] = float(a[0]) / float(a[1])
        elif a:
            _progress[slot] = float(a[0])

    return fn(*args, progress=progress, cancel=cancel)


def warm() -> float:
    """In the worker: import the algorithms and load the field's compiled kernels (numba cache)
    by running the field once on a small bundled demo. Returns the seconds it took."""
    t = time.perf_counter()
    import algorithms.repair  # noqa: F401
    from algorithms.bridges import find_candidate_bridges
    from algorithms.demos import all_demos
    from algorithms.io import load_model
    from algorithms.params import FieldParams

    demos = [d for d in all_demos().values() if d.kind == "repair"]
    if demos:
        small = min(demos, key=lambda d: d.path.stat().st_size)
        model = load_model(small.path)
        for mode in ("light", "full"):
            find_candidate_bridges(model, FieldParams(mode=mode))
    return time.perf_counter() - t


_SHARED: list = []


def shared_runner() -> ProcessRunner:
    """The process-wide runner (started, and warmed, on first use; ended at exit). Windows share
    it: a window's closing cancels its own calls, the processes stay for the next window."""
    if not _SHARED:
        import atexit

        r = ProcessRunner()
        _SHARED.append(r)
        atexit.register(r.shutdown)
    return _SHARED[0]


class ProcessRunner:
    """A pool of spawned worker processes with per-call cancel and progress."""

    def __init__(self, workers: int = 2, *, warm_up: bool = True) -> None:
        ctx = mp.get_context("spawn")
        self._flags = ctx.RawArray("b", SLOTS)
        self._progress = ctx.RawArray("d", SLOTS)
        self._ctx = ctx
        self.workers = workers
        self._next = 0
        self._lock = threading.Lock()
        self._pool = self._new_pool()
        self.warmed = [self._pool.submit(warm) for _ in range(workers)] if warm_up else []

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(self.workers, mp_context=self._ctx, initializer=_init,
                                   initargs=(self._flags, self._progress))

    def call(self, fn: Callable, args: tuple, *, progress: Callable | None = None,
             cancel: Callable[[], bool] | None = None, control: bool = True, poll: float = 0.02):
        """Run fn(*args) in a worker process and wait for it (call this from a worker thread).

        ``cancel()`` is polled: once it returns True the worker is told to stop (the algorithm
        raises Cancelled there) and Cancelled is raised here at once. ``progress(fraction)``
        relays the worker's reports.
        """
        with self._lock:  # calls come from several worker threads
            slot = self._next % SLOTS
            self._next += 1
        self._flags[slot] = 0
        self._progress[slot] = 0.0
        try:
            fut = self._pool.submit(_run, slot, fn, args, control)
        except BrokenProcessPool:  # a worker died earlier: start new ones
            self._pool = self._new_pool()
            fut = self._pool.submit(_run, slot, fn, args, control)
        last = 0.0  # nothing reported yet
        while True:
            try:
                return fut.result(timeout=poll)
            except FutureTimeout:
                pass
            except BrokenProcessPool as exc:
                self._pool = self._new_pool()
                raise RuntimeError("a worker process died during the computation (it was restarted)") from exc
            if cancel is not None and cancel():
                self._flags[slot] = 1
                fut.cancel()
                raise Cancelled("cancelled")
            if progress is not None and self._progress[slot] != last:
                last = self._progress[slot]
                progress(last)

    def alive(self) -> int:
        """Worker processes still running."""
        procs = getattr(self._pool, "_processes", None) or {}
        return sum(1 for p in procs.values() if p.is_alive())

    def shutdown(self, timeout: float = 10.0) -> None:
        """Tell every call to stop, then end the worker processes."""
        for i in range(SLOTS):
            self._flags[i] = 1
        procs = list((getattr(self._pool, "_processes", None) or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        deadline = time.perf_counter() + timeout
        for p in procs:
            p.join(max(0.0, deadline - time.perf_counter()))
            if p.is_alive():
                p.terminate()
                p.join(1.0)

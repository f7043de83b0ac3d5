"""The explorer's worker processes: results, progress, cancel, and a caller that is never held
by the GIL of the computation (the field's compiled kernels hold it while they run)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from viewer_fakes import busy_python, slow_count

from algorithms.records import Cancelled
from viewer.procpool import ProcessRunner


@pytest.fixture(scope="module")
def runner():
    r = ProcessRunner(workers=1, warm_up=False)
    yield r
    r.shutdown()
    assert r.alive() == 0


def test_result_and_progress(runner):
    seen = []
    assert runner.call(slow_count, (5, 0.02), progress=seen.append) == 5
    assert seen and all(0 < f <= 1 for f in seen) and seen == sorted(seen)


def test_cancel_stops_the_call_in_the_process(runner):
    flag = threading.Event()
    threading.Timer(0.3, flag.set).start()
    t0 = time.perf_counter()
    with pytest.raises(Cancelled):
        runner.call(slow_count, (1000, 0.01), cancel=flag.is_set)
    assert time.perf_counter() - t0 < 1.0
    # the process stopped the cancelled call: the next call runs at once
    t0 = time.perf_counter()
    assert runner.call(slow_count, (1, 0.0)) == 1
    assert time.perf_counter() - t0 < 1.0


def test_the_caller_thread_is_never_held(runner):
    """While 1.5 s of GIL-holding work runs in the process, this thread keeps beating."""
    done = []
    th = threading.Thread(target=lambda: done.append(runner.call(busy_python, (1.5,), control=False)))
    beats = []
    th.start()
    while th.is_alive():
        beats.append(time.perf_counter())
        time.sleep(0.005)
    th.join()
    gaps = np.diff(beats)
    print(f"main thread: {len(beats)} beats, longest gap {gaps.max() * 1000:.0f} ms")
    assert done and done[0] > 0 and gaps.max() < 0.1

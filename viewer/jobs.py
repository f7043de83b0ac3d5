"""The algorithm calls the explorer runs in its worker, as ``fn(progress=, cancel=)`` closures.

The field (``algorithms.bridges``) is imported when first needed; while it is missing the window
still opens, draws the input and says why there are no bridges.
"""

from __future__ import annotations

from collections.abc import Callable

from algorithms.io import load_model
from algorithms.mesh import Icadm
from algorithms.params import FieldParams


def preload() -> None:
    """Import on the GUI thread what the jobs import lazily.

    A first import inside a worker thread runs PySide6's import hook there, which can crash the
    interpreter (seen: scipy.fft imported by trimesh in a QThread). So import it all up front.
    """
    import importlib

    for name in ("scipy.fft", "scipy.linalg", "scipy.optimize", "scipy.sparse", "scipy.sparse.csgraph",
                 "scipy.spatial", "trimesh", "trimesh.exchange.load", "trimesh.exchange.ply", "trimesh.exchange.obj",
                 "trimesh.exchange.stl", "trimesh.exchange.off", "trimesh.bounds", "trimesh.nsphere",
                 "algorithms.normalize", "algorithms.topology", "algorithms.boundary", "algorithms.metrics",
                 "algorithms.repair", "algorithms.repair_field", "algorithms.darning", "algorithms.darning.fair",
                 "algorithms.darning.liepa", "algorithms.darning.fan", "algorithms.darning.refine",
                 "algorithms.holes", "algorithms.bridge_graph", "scipy.sparse.linalg"):
        try:
            importlib.import_module(name)
        except ImportError:
            pass
    try:
        field_api()
    except ImportError:
        pass


def field_api():
    """(find_candidate_bridges, trace_from_vertex), or raises ImportError with a clear message."""
    try:
        from algorithms.bridges import find_candidate_bridges, trace_from_vertex
    except ImportError as exc:
        raise ImportError(f"the force-line field (algorithms.bridges) is not available: {exc}") from exc
    return find_candidate_bridges, trace_from_vertex


def default_find(model: Icadm, params: FieldParams, *, progress=None, cancel=None):
    find, _ = field_api()
    return find(model, params, progress=progress, cancel=cancel)


def default_trace(model: Icadm, params: FieldParams, vertex: int):
    _, trace = field_api()
    return trace(model, params, vertex)


def default_repair(model: Icadm, params, *, progress=None, cancel=None):
    """algorithms.repair.repair with RepairParams (the field's parameters and the darning method)."""
    from algorithms.repair import repair

    return repair(model, params, progress=progress, cancel=cancel)


def repair_job(repair: Callable, model: Icadm, params, runner=None) -> Callable:
    """params: RepairParams; the result carries what it was computed for (stale results are dropped)."""
    def fn(progress=None, cancel=None):
        return model, params, _via(runner, repair, (model, params), progress, cancel)

    return fn


def load_job(path: str, points: str | None) -> Callable:
    def fn(progress=None, cancel=None):
        return load_model(path, points=points)

    return fn


def _via(runner, fn: Callable, args: tuple, progress, cancel, *, control: bool = True):
    """fn(*args) here (a worker thread) or in a worker process of ``runner`` (a ProcessRunner)."""
    if runner is None:
        return fn(*args, progress=progress, cancel=cancel) if control else fn(*args)
    return runner.call(fn, args, progress=progress, cancel=cancel, control=control)


def bridges_job(find: Callable, model: Icadm, params: FieldParams, runner=None) -> Callable:
    def fn(progress=None, cancel=None):
        return model, params, _via(runner, find, (model, params), progress, cancel)

    return fn


def trace_job(trace: Callable, model: Icadm, params: FieldParams, vertex: int, runner=None) -> Callable:
    def fn(progress=None, cancel=None):
        return model, params, vertex, _via(runner, trace, (model, params, vertex), progress, cancel, control=False)

    return fn

"""Compile the numba kernels ahead of the first real run.

The field, tracing and darning kernels are compiled by numba on their first call and cached on
disk (``cache=True``: next to the modules, or in ``NUMBA_CACHE_DIR``). Compiling all of them takes
about a minute on a 2-core machine, so a fresh install's first ``bridgefield repair`` would spend
a minute compiling before it repairs anything (a Bunny-1-sized repair itself takes under 2 s).
``warm`` runs every kernel once on small inputs, with the argument types of real runs, so the
compiled code is in the cache before a user needs it; ``.ci/setup`` runs it (``bridgefield
warmup``). Run again with the cache in place it only loads the cache (a few seconds).

The inputs: the repair pipeline in both field modes on two bundled demos (islands with free
points, a lost handle), plus the kernels those do not reach: the RBF implicit of thin parts, the
angle smoothing of refine_angles, the field's serial path for small point sets. tests/test_warmup.py
checks that after ``warm`` a repair of other shapes compiles nothing more.
"""

from __future__ import annotations

import importlib
import pkgutil
import time
from collections.abc import Callable, Iterator

import numpy as np


def kernels() -> Iterator[tuple[str, object]]:
    """(qualified name, dispatcher) of every numba-compiled function of the package."""
    from numba.core.registry import CPUDispatcher

    import algorithms

    for info in pkgutil.walk_packages(algorithms.__path__, "algorithms."):
        if info.name.endswith("__main__") or info.name.startswith("algorithms.cli"):
            continue
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            if isinstance(obj, CPUDispatcher) and obj.__module__ == info.name:
                yield f"{info.name}.{name}", obj


def _repairs() -> None:
    from .cases import demo_cases
    from .normalize import normalize
    from .params import FieldParams
    from .repair import RepairParams, repair

    for case in demo_cases():
        if case.name not in ("two-caps", "cut-torus"):
            continue
        for mode in ("light", "full"):
            model = normalize(case.incomplete.vertices, case.incomplete.faces, extra_points=case.free_points)
            repair(model, RepairParams(field=FieldParams(mode=mode)))


def _rbf() -> None:
    """The r^3 RBF implicit (darning/implicit.py: holes across thin parts)."""
    from .cases import icosphere
    from .darning.implicit import fit_rbf

    s = icosphere(1)
    v = np.asarray(s.vertices)
    fit_rbf(v, v / np.linalg.norm(v, axis=1, keepdims=True), spacing=0.5)


def _angles() -> None:
    """refine_angles' compiled smoothing of bad triangles (refine_kernels.smooth_bad) and its grid search
    for a vertex's best place (refine._move_best: refine_kernels.grid_search)."""
    import importlib

    from .darning.refine_kernels import corner_angles, smooth_bad

    refine = importlib.import_module(".darning.refine", __package__)  # the package exports a function so named

    p = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0.05, 0], [0.5, 1, 0], [0.5, -1, 0]])
    f = np.array([[0, 1, 2], [0, 2, 3], [2, 1, 3], [1, 0, 4]], dtype=np.int64)
    free = np.array([False, False, True, False, False])
    smooth_bad(p, f, free, np.array([0], dtype=np.int64))
    corner_angles(p, f)
    star = f[(f == 2).any(axis=1)]
    refine._move_best(p, star, 2, float(corner_angles(p, star).min()))


def _liepa() -> None:
    """Liepa's own weight (darning/liepa.py), which the darning takes where a minimum area fill folds."""
    from .darning.liepa import triangulate

    t = np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
    p = np.c_[np.cos(t), np.sin(t), 0.3 * np.sin(2 * t)]
    triangulate(p, weight="dihedral", outside_normals=np.tile([0.0, 0.0, 1.0], (8, 1)))


STEPS: tuple[tuple[str, Callable[[], None]], ...] = (
    ("repair pipeline (light and full field, islands, a lost handle)", _repairs),
    ("Liepa's weight (folded fills)", _liepa),
    ("RBF implicit of thin parts", _rbf),
    ("angle smoothing", _angles),
)


def warm(progress: Callable[[str], None] | None = None) -> dict:
    """Run every kernel once; returns {"seconds", "compiled": the kernels compiled now (not
    loaded from the cache), "kernels": how many the package has}."""
    from numba.core.event import install_recorder

    t0 = time.perf_counter()
    with install_recorder("numba:compile") as rec:
        for label, step in STEPS:
            if progress is not None:
                progress(label)
            step()
    compiled = sorted({f'{ev.data["dispatcher"].py_func.__module__}.{ev.data["dispatcher"].py_func.__qualname__}'
                       for _, ev in rec.buffer if ev.is_start and "dispatcher" in ev.data})
    return {"seconds": time.perf_counter() - t0, "compiled": compiled, "kernels": sum(1 for _ in kernels())}

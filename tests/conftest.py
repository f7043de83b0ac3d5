"""Shared test helpers: where the real meshes are (../shared/data beside the project)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("BRIDGEFIELD_DATA", ROOT.parent / "shared" / "data"))


def data_file(name: str) -> Path:
    """Path of a shared mesh; skips the test when the shared folder is absent."""
    p = DATA / name
    if not p.exists():
        pytest.skip(f"shared data {p} not present")
    return p


@pytest.hookimpl(hookwrapper=True, trylast=True)
def pytest_runtest_teardown(item, nextitem):
    """After a test's fixtures are torn down (pytest-qt has closed its widgets), delete the Qt
    objects waiting for deleteLater and collect garbage *now*, in a known state. Left to chance,
    Python's collector finalises a closed window's VTK/Qt objects in the middle of a later test
    (a segfault seen once while the next window built its menus)."""
    yield
    import sys

    if "PySide6.QtWidgets" not in sys.modules:
        return
    import gc

    from PySide6.QtCore import QCoreApplication, QEvent
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance()
    if app is None:
        return
    for _ in range(2):
        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
        app.processEvents()
        gc.collect()

"""Starting the explorer window."""

from __future__ import annotations

import sys


def run_app(path: str | None = None, demo: str | None = None, points: str | None = None) -> int:
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("Bridgefield")
    app.setOrganizationName("Bridgefield")
    from .main_window import MainWindow

    win = MainWindow()
    win.show()
    if path:
        win.open_path(path, points=points)
    elif demo:
        win.open_demo(demo)
    return int(app.exec())

"""Starting the explorer window."""

from __future__ import annotations

import sys


def run_app(path: str | None = None, demo: str | None = None, points: str | None = None) -> int:
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("Bridgefield")
    app.setOrganizationName("Bridgefield")
    from PySide6.QtCore import QTimer

    from .main_window import MainWindow

    win = MainWindow()
    win.show()
    # open the input once the event loop has painted the first frame (loading imports and
    # starts the worker processes' first job: the window shows first)
    if path:
        QTimer.singleShot(50, lambda: win.open_path(path, points=points))
    elif demo:
        QTimer.singleShot(50, lambda: win.open_demo(demo))
    # Ctrl+C in the terminal closes the window cleanly (workers stopped); the timer lets Python
    # run its signal handler while Qt's loop runs
    import signal

    signal.signal(signal.SIGINT, lambda *_: (win.close(), app.quit()))
    tick = QTimer()
    tick.timeout.connect(lambda: None)
    tick.start(250)
    return int(app.exec())

"""The explorer's main window (first version: the 3D view of an incomplete model)."""

from __future__ import annotations

from PySide6.QtWidgets import QMainWindow, QMessageBox
from pyvistaqt import QtInteractor

from algorithms.demos import demo as find_demo
from algorithms.io import load_model

from .scene import draw_model, frame_camera


class MainWindow(QMainWindow):
    def __init__(self) -> None:
        super().__init__()
        self.setWindowTitle("Bridgefield")
        self.resize(1280, 860)
        self.plotter = QtInteractor(self)
        self.plotter.set_background("white", top="#dfe7ee")
        self.setCentralWidget(self.plotter.interactor)
        self.model = None

    def open_path(self, path: str, points: str | None = None) -> None:
        try:
            self.model = load_model(path, points=points)
        except Exception as exc:  # shown to the user; the window keeps working
            QMessageBox.warning(self, "Bridgefield", str(exc))
            return
        draw_model(self.plotter, self.model)
        frame_camera(self.plotter, self.model)
        self.setWindowTitle(f"Bridgefield - {path}")

    def open_demo(self, name: str) -> None:
        self.open_path(str(find_demo(name).path))

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        self.plotter.close()
        super().closeEvent(event)

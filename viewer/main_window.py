"""The explorer's main window: the 3D view in the centre, docks for Parameters, Bridges,
Inspector, Timeline and Plot, a status bar with progress and Cancel, menus and shortcuts.

Data flows one way: file -> Icadm -> (worker) field result [-> repair] -> model -> views.
Widgets write new parameters through the model; every edit recomputes in the worker (debounced,
stale jobs cancelled and their results dropped) and the views update from the model's signals.
Once the user ran Repair (F6), edits recompute the repair too.
"""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path

from PySide6.QtCore import QEvent, QSettings, Qt, QTimer
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QDialog,
    QDockWidget,
    QFileDialog,
    QLabel,
    QMainWindow,
    QMenu,
    QMessageBox,
    QProgressBar,
    QPushButton,
)

from algorithms.demos import all_demos
from algorithms.demos import demo as find_demo
from algorithms.io import save_mesh

from . import jobs
from .model import ExplorerModel, Source
from .panels.bridges import BridgesPanel
from .panels.inspector import InspectorPanel
from .panels.parameters import ParametersPanel
from .panels.plot import PlotPanel
from .panels.timeline import TimelinePanel
from .scene import LAYER_TITLES, LAYERS
from .scene_view import SceneView
from .session import load_session, save_session, session_dict
from .worker import Worker

MESH_FILTER = "Meshes (*.ply *.obj *.stl *.off);;All files (*)"
POINTS_FILTER = "Point clouds (*.ply *.xyz *.txt *.csv *.obj *.off);;All files (*)"
MAX_RECENT = 10


class MainWindow(QMainWindow):
    def __init__(self, *, settings: QSettings | None = None, find=None, trace=None, repair=None,
                 processes: bool | None = None) -> None:
        super().__init__()
        self.t_created = time.perf_counter()
        self.setWindowTitle("Bridgefield")
        self.resize(1400, 900)
        self.setAcceptDrops(True)
        self.settings = settings if settings is not None else QSettings("Bridgefield", "explorer")
        self.find = find or jobs.default_find  # injectable for tests
        self.trace = trace or jobs.default_trace
        self.repair_fn = repair or jobs.default_repair
        # the real algorithms run in worker processes (their compiled kernels hold the GIL);
        # injected stand-ins (tests) run in worker threads
        if processes is None:
            processes = find is None and trace is None and repair is None
        self.runner = None
        if processes:
            from .procpool import shared_runner

            self.runner = shared_runner()
        self.workspaces: list = []  # hybrid / F-rep workspace windows opened from the Demos menu
        self.model = ExplorerModel(self)
        self.worker = Worker(self)
        self.errors: list[str] = []  # every error shown to the user, newest last
        self.last_timing: dict[str, float] = {}
        self._pending_session: dict | None = None
        self._error_box: QMessageBox | None = None
        self.compare_window = None

        self.scene = SceneView(self.model, self)
        self.setCentralWidget(self.scene.widget)
        self._make_docks()
        self._make_status_bar()
        self._make_menus()
        self._connect()

    # ================================================================ construction
    @staticmethod
    def _native(widget) -> None:
        """Give a widget its own native window. Qt composes a window that holds an OpenGL widget
        (the 3D view) with OpenGL on every repaint of any of its widgets: under software GL that
        cost ~100 ms per progress-bar tick. A native child window repaints with a raster flush."""
        widget.setAttribute(Qt.WA_NativeWindow, True)

    def _dock(self, title: str, widget, area) -> QDockWidget:
        d = QDockWidget(title, self)
        d.setObjectName(title)
        d.setWidget(widget)
        self._native(widget)
        self.addDockWidget(area, d)
        return d

    def _make_docks(self) -> None:
        m = self.model
        self.parameters = ParametersPanel(m)
        self.bridges = BridgesPanel(m)
        self.inspector = InspectorPanel(m)
        self.timeline = TimelinePanel(m)
        self.plot = PlotPanel(m)
        self.dock_parameters = self._dock("Parameters", self.parameters, Qt.LeftDockWidgetArea)
        self.dock_inspector = self._dock("Inspector", self.inspector, Qt.LeftDockWidgetArea)
        self.dock_bridges = self._dock("Bridges", self.bridges, Qt.RightDockWidgetArea)
        self.dock_plot = self._dock("Plot", self.plot, Qt.RightDockWidgetArea)
        self.dock_timeline = self._dock("Timeline", self.timeline, Qt.BottomDockWidgetArea)
        self.resizeDocks([self.dock_parameters, self.dock_bridges], [300, 430], Qt.Horizontal)
        self.resizeDocks([self.dock_bridges, self.dock_plot], [420, 260], Qt.Vertical)

    def _make_status_bar(self) -> None:
        sb = self.statusBar()
        self.status = QLabel("Ready")
        self.progress = QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setMaximumWidth(220)
        self.progress.setVisible(False)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setToolTip("stop the running computation (Esc)")
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.cancel)
        self.timing = QLabel("")
        sb.addWidget(self.status, 1)
        sb.addPermanentWidget(self.timing)
        sb.addPermanentWidget(self.progress)
        sb.addPermanentWidget(self.cancel_button)
        self._native(sb)

    def _action(self, menu, text: str, slot, shortcut=None, *, tip: str = "", checkable=False) -> QAction:
        a = QAction(text, self)
        if shortcut is not None:
            a.setShortcut(QKeySequence(shortcut))
            a.setShortcutContext(Qt.WindowShortcut)
        if tip:
            a.setStatusTip(tip)
            a.setToolTip(tip)
        a.setCheckable(checkable)
        if checkable:
            a.toggled.connect(slot)
        else:
            a.triggered.connect(lambda *_: slot())
        menu.addAction(a)
        self.addAction(a)  # shortcuts work whatever has the focus
        return a

    def _menu(self, parent, title: str) -> QMenu:
        """A menu made here and added to ``parent`` (the menu bar or a menu).

        Menus and actions are built in Python rather than taken from ``addMenu(title)`` /
        ``addAction(text)``: those return the C++ object through Shiboken's address map, which
        once (CI, after many VTK views) still held a stale wrapper of a deleted
        QOffscreenSurface at the new action's address, so the "action" had no setStatusTip."""
        m = QMenu(title, parent)
        parent.addMenu(m)
        return m

    def _plain_action(self, menu: QMenu, text: str) -> QAction:
        """An action owned by ``menu`` (menu.clear() deletes it: the demo and recent lists are
        refilled), without the window-wide shortcut registration of ``_action``."""
        a = QAction(text, menu)
        menu.addAction(a)
        return a

    def _make_menus(self) -> None:
        mb = self.menuBar()
        f = self._menu(mb, "&File")
        self.act_open = self._action(f, "&Open mesh…", self.open_dialog, QKeySequence.Open)
        self.act_points = self._action(f, "Open point &cloud…", self.open_points_dialog, "Ctrl+Shift+O",
                                       tip="add free points from a point cloud to the current mesh")
        self.recent_menu = self._menu(f, "Open &recent")
        self.demos_menu_file = self._menu(f, "&Demos")
        f.addSeparator()
        self.act_save_input = self._action(f, "Save &mesh (normalised input)…", self.save_mesh_dialog, "Ctrl+S",
                                           tip="the input as normalised, with its free points")
        self.act_save_repaired = self._action(f, "Save &repaired mesh…", self.save_repaired_dialog, "Ctrl+Alt+R",
                                              tip="the repaired surface (after Repair, F6)")
        self.act_save_repaired.setEnabled(False)
        self.act_shot = self._action(f, "Export &screenshot (PNG)…", self.screenshot_dialog, "Ctrl+Shift+S")
        self.act_anim = self._action(f, "Export &animation (GIF/MP4)…", self.animation_dialog, "Ctrl+Shift+E")
        f.addSeparator()
        self.act_save_session = self._action(f, "Save sess&ion…", self.save_session_dialog, "Ctrl+Alt+S")
        self.act_load_session = self._action(f, "&Load session…", self.load_session_dialog, "Ctrl+Alt+O")
        f.addSeparator()
        self._action(f, "&Quit", self.close, QKeySequence.Quit)

        e = self._menu(mb, "&Edit")
        self.act_undo = self._action(e, "&Undo parameter edit", self.model.undo, "Ctrl+Z")
        self.act_redo = self._action(e, "&Redo parameter edit", self.model.redo, "Ctrl+Shift+Z")
        self.act_undo.setEnabled(False)
        self.act_redo.setEnabled(False)
        e.addSeparator()
        self._action(e, "Re&compute", self.recompute, "F5")
        self.act_repair = self._action(e, "&Repair", self.run_repair, "F6",
                                       tip="run the repair pipeline (bridges, hole splitting, darning); "
                                           "parameter edits then recompute it")
        self.act_cancel = self._action(e, "&Cancel computation", self.cancel, "Esc")

        v = self._menu(mb, "&View")
        self.layer_actions: dict[str, QAction] = {}
        for name in LAYERS:
            a = self._action(v, LAYER_TITLES[name], lambda on, n=name: self.set_layer_visible(n, on),
                             f"Ctrl+{LAYERS.index(name) + 1}", checkable=True)
            a.blockSignals(True)
            a.setChecked(True)
            a.blockSignals(False)
            self.layer_actions[name] = a
        v.addSeparator()
        self._action(v, "&Reset camera", self.reset_camera, "Ctrl+R")
        self._action(v, "Co&mpare side by side…", self.open_compare, "Ctrl+K",
                     tip="two linked views of the same input with different parameters")
        v.addSeparator()
        for d in (self.dock_parameters, self.dock_inspector, self.dock_bridges, self.dock_plot, self.dock_timeline):
            v.addAction(d.toggleViewAction())

        p = self._menu(mb, "&Playback")
        tl = self.timeline
        self._action(p, "&Play / pause", tl.toggle_play, "Space")
        self._action(p, "Step &forward", tl.step_forward, ".")
        self._action(p, "Step &back", tl.step_back, ",")
        self._action(p, "F&irst step", tl.first, "Home")
        self._action(p, "&Last step", tl.last, "End")
        self.act_loop = self._action(p, "L&oop", tl.loop.setChecked, "L", checkable=True)
        tl.loop.toggled.connect(self.act_loop.setChecked)
        p.addSeparator()
        self.act_stages = self._action(p, "Repair &stages on the timeline",
                                       lambda on: self.model.set_timeline_mode("stages" if on else "line"), "T",
                                       checkable=True, tip="the timeline plays the repair's stages instead of "
                                                           "the force line")
        self.act_stages.setEnabled(False)

        self.demos_menu = self._menu(mb, "&Demos")
        self._fill_demos()
        h = self._menu(mb, "&Help")
        self._action(h, "&Shortcuts", self.show_shortcuts, "F1")
        self._action(h, "&About Bridgefield", self.show_about)
        self._fill_recent()
        for m in (f, e, v, p, self.demos_menu, h, self.recent_menu, self.demos_menu_file):
            m.aboutToHide.connect(self._repaint_frame)

    def _repaint_frame(self) -> None:
        """Repaint the window's own areas (dock separators) once a menu or a dialog went away:
        with the docks in native windows, X leaves stale pixels there without a compositor."""
        QTimer.singleShot(0, self.update)

    def changeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        if event.type() == QEvent.ActivationChange and self.isActiveWindow():
            self._repaint_frame()
        super().changeEvent(event)

    def _fill_demos(self) -> None:
        for menu in (self.demos_menu, self.demos_menu_file):
            menu.clear()
            for name, d in all_demos().items():
                a = self._plain_action(menu, f"{name}  ({d.kind})")
                a.setStatusTip(d.description)
                a.setToolTip(d.description)
                a.triggered.connect(lambda *_, n=name: self.open_demo(n))

    def _connect(self) -> None:
        m, w = self.model, self.worker
        m.paramsChanged.connect(self._params_changed)
        m.undoStateChanged.connect(lambda u, r: (self.act_undo.setEnabled(u), self.act_redo.setEnabled(r)))
        m.resultChanged.connect(self._result_shown)
        w.started.connect(self._job_started)
        w.progress.connect(self._job_progress)
        w.finished.connect(self._job_finished)
        w.failed.connect(self._job_failed)
        w.cancelled.connect(self._job_cancelled)
        w.busyChanged.connect(self._busy)
        self.parameters.invalid.connect(lambda msg: self.show_error("Invalid parameter", msg))
        self.parameters.layerToggled.connect(self.set_layer_visible)
        self.scene.pickedBoundary.connect(self.trace_from)
        self.scene.pickedBridge.connect(self.model.select)
        self.timeline.playingChanged.connect(self.scene.set_playing)
        m.darningChanged.connect(self._darning_changed)
        m.repairChanged.connect(self._repair_shown)
        m.timelineModeChanged.connect(self._timeline_mode_shown)
        self.parameters.repair_button.clicked.connect(self.run_repair)

    # ================================================================ files
    def open_path(self, path: str, points: str | None = None, *, demo: str | None = None) -> None:
        """Load a mesh (in the worker); it replaces the current input when it lands."""
        if not Path(path).exists():
            self.show_error("Cannot open", f"{path}: no such file")
            return
        if demo is None:  # a bundled demo opened by its path (recent files, a dialog) keeps its name
            here = Path(path).resolve()
            demo = next((n for n, d in all_demos().items() if d.kind == "repair" and d.path.resolve() == here), None)
        self._loading = Source(str(path), points, demo)
        self.status.setText(f"Loading {Path(path).name}…")
        jobs.preload()  # first imports never happen in a worker thread (done once, after the first frame)
        self.worker.submit("load", jobs.load_job(str(path), points))

    def open_demo(self, name: str):
        """A repair demo opens here; a hybrid or F-rep demo opens its workspace window (returned)."""
        try:
            d = find_demo(name)
        except KeyError as exc:
            self.show_error("Unknown demo", str(exc))
            return None
        if d.kind in ("hybrid", "frep"):
            return self.open_workspace(d.kind, name)
        self.open_path(str(d.path), demo=name)
        return None

    def open_workspace(self, kind: str, demo: str | None = None):
        from .workspaces import open_workspace

        try:
            w = open_workspace(kind, self, demo=demo)
        except Exception as exc:
            self.show_error("Cannot open the workspace", f"{type(exc).__name__}: {exc}")
            return None
        self.workspaces = [x for x in self.workspaces if _alive(x)] + [w]
        w.destroyed.connect(lambda *_: setattr(self, "workspaces", [x for x in self.workspaces
                                                                      if x is not w and _alive(x)]))
        self.status.setText(f"Opened the {kind} workspace on demo {demo}")
        return w

    def open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open mesh", self._last_dir(), MESH_FILTER)
        if path:
            self.open_path(path)

    def open_points_dialog(self) -> None:
        if self.model.source is None:
            self.show_error("No mesh", "Open a mesh first, then add a point cloud to it.")
            return
        path, _ = QFileDialog.getOpenFileName(self, "Open point cloud", self._last_dir(), POINTS_FILTER)
        if path:
            self.open_path(self.model.source.path, points=path, demo=self.model.source.demo)

    def _last_dir(self) -> str:
        return str(self.settings.value("last_dir", str(Path.cwd())))

    def recent_files(self) -> list[str]:
        v = self.settings.value("recent", [])
        if isinstance(v, str):
            v = [v]
        return [str(x) for x in (v or [])]

    def _remember(self, path: str, *, demo: bool = False) -> None:
        p = str(Path(path).resolve())
        rec = [p] + [r for r in self.recent_files() if r != p]
        self.settings.setValue("recent", rec[:MAX_RECENT])
        if not demo:  # dialogs never default to the bundled assets folder
            self.settings.setValue("last_dir", str(Path(p).parent))
        self._fill_recent()

    def _fill_recent(self) -> None:
        self.recent_menu.clear()
        rec = self.recent_files()
        for p in rec:
            a = self._plain_action(self.recent_menu, p)
            a.triggered.connect(lambda *_, q=p: self.open_path(q))
        if not rec:
            self._plain_action(self.recent_menu, "(none)").setEnabled(False)
        else:
            self.recent_menu.addSeparator()
            self._plain_action(self.recent_menu, "Clear list").triggered.connect(self._clear_recent)

    def _clear_recent(self) -> None:
        self.settings.setValue("recent", [])
        self._fill_recent()

    def dragEnterEvent(self, event) -> None:  # noqa: N802
        if event.mimeData().hasUrls():
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:  # noqa: N802
        urls = [u.toLocalFile() for u in event.mimeData().urls() if u.isLocalFile()]
        if not urls:
            return
        if urls[0].endswith(".json"):
            self.load_session_file(urls[0])
        else:
            self.open_path(urls[0], points=urls[1] if len(urls) > 1 else None)
        event.acceptProposedAction()

    def save_mesh_dialog(self) -> None:
        if self.model.icadm is None:
            self.show_error("Nothing to save", "Open a mesh first.")
            return
        path, _ = QFileDialog.getSaveFileName(self, "Save mesh", self._last_dir(), MESH_FILTER)
        if path:
            try:
                save_mesh(self.model.icadm.mesh, path, force=True, free_points=self.model.icadm.free_points)
                self.status.setText(f"Saved {path}")
            except Exception as exc:
                self.show_error("Cannot save", str(exc))

    def save_repaired_dialog(self) -> None:
        """The file dialog asks before replacing a file; only then is it overwritten."""
        if self.model.repair is None:
            self.show_error("Nothing to save", "Run the repair first (Edit > Repair, F6).")
            return
        dlg = QFileDialog(self, "Save repaired mesh", self._last_dir(), MESH_FILTER)
        dlg.setAcceptMode(QFileDialog.AcceptSave)
        dlg.setDefaultSuffix("ply")
        if self.model.source is not None:
            dlg.selectFile(Path(self.model.source.path).stem + "-repaired.ply")
        if dlg.exec() != QDialog.Accepted or not dlg.selectedFiles():
            return
        self.save_repaired(dlg.selectedFiles()[0], force=True)  # the dialog confirmed any overwrite

    def save_repaired(self, path: str, *, force: bool = False) -> bool:
        """Write the repaired surface (PLY/OBJ/STL/OFF); an existing file only with force."""
        r = self.model.repair
        if r is None:
            self.show_error("Nothing to save", "Run the repair first (Edit > Repair, F6).")
            return False
        try:
            out = save_mesh(r.mesh, path, force=force)
        except Exception as exc:
            self.show_error("Cannot save", str(exc))
            return False
        self.status.setText(f"Saved the repaired mesh to {out} ({r.mesh.n_faces} faces)")
        return True

    def screenshot_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Export screenshot", self._last_dir(), "PNG image (*.png)")
        if path:
            self.save_screenshot(path)

    def save_screenshot(self, path: str) -> None:
        if not path.lower().endswith(".png"):
            path += ".png"
        try:
            self.scene.save_png(path)
            self.status.setText(f"Saved {path}")
        except Exception as exc:
            self.show_error("Cannot save screenshot", str(exc))

    def animation_formats(self) -> list[str]:
        fm = ["GIF animation (*.gif)"]
        if importlib.util.find_spec("imageio_ffmpeg") is not None:
            fm.append("MP4 video (*.mp4)")
        return fm

    def animation_dialog(self) -> None:
        if self.model.line is None:
            self.show_error("No animation", "Select a bridge or click a boundary point to trace a line first.")
            return
        path, _ = QFileDialog.getSaveFileName(self, "Export animation", self._last_dir(),
                                              ";;".join(self.animation_formats()))
        if path:
            self.export_animation(path)

    def export_animation(self, path: str, *, max_frames: int = 120, fps: int = 24) -> int:
        """Render the line on the timeline step by step into a GIF (or MP4); returns frames written."""
        import imageio.v2 as imageio

        line = self.model.line
        if line is None:
            raise ValueError("no force line on the timeline")
        if not path.lower().endswith((".gif", ".mp4")):
            path += ".gif"
        self.timeline.pause()
        stride = max(1, -(-line.steps // max_frames))
        ks = list(range(0, line.steps, stride))
        if ks[-1] != line.steps - 1:
            ks.append(line.steps - 1)
        keep = self.model.frame
        frames = []
        try:
            for k in ks:
                self.model.set_frame(k)
                img = self.scene.grab()
                frames.append(img[: img.shape[0] // 2 * 2, : img.shape[1] // 2 * 2])
            if path.lower().endswith(".mp4"):
                imageio.mimsave(path, frames, fps=fps)
            else:
                imageio.mimsave(path, frames, duration=1000 / fps, loop=0)
        except Exception as exc:
            self.show_error("Cannot export animation", str(exc))
            return 0
        finally:
            self.model.set_frame(keep)
        self.status.setText(f"Saved {path} ({len(frames)} frames)")
        return len(frames)

    # ================================================================ sessions
    def session(self) -> dict:
        return session_dict(self.model.source, self.model.params, self.scene.camera_state(),
                            layers=dict(self.scene.layers.visible), selection=self.model.selection,
                            frame=self.model.frame, darning=self.model.darning)

    def save_session_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save session", self._last_dir(), "Session (*.json)")
        if path:
            self.save_session_file(path if path.endswith(".json") else path + ".json")

    def save_session_file(self, path: str) -> None:
        try:
            save_session(path, self.session())
            self.status.setText(f"Saved session {path}")
        except Exception as exc:
            self.show_error("Cannot save session", str(exc))

    def load_session_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Load session", self._last_dir(), "Session (*.json)")
        if path:
            self.load_session_file(path)

    def load_session_file(self, path: str) -> None:
        try:
            data = load_session(path)
        except Exception as exc:
            self.show_error("Cannot load session", str(exc))
            return
        self.model.set_params(data["params"])
        if data.get("darning"):
            self.model.set_darning(data["darning"])
        for name, on in data.get("layers", {}).items():
            if name in self.layer_actions:
                self.layer_actions[name].setChecked(bool(on))
        inp = data.get("input")
        same = (inp is not None and self.model.source is not None
                and Path(inp["path"]).resolve() == Path(self.model.source.path).resolve()
                and inp.get("points") == (str(Path(self.model.source.points).resolve())
                                          if self.model.source.points else None))
        if inp is None or same:
            self._apply_session_view(data)
        else:
            self._pending_session = data  # applied when the input has loaded
            self.open_path(inp["path"], points=inp.get("points"), demo=inp.get("demo"))

    def _apply_session_view(self, data: dict) -> None:
        if data.get("camera"):
            self.scene.set_camera_state(data["camera"])

    # ================================================================ computing
    def recompute(self) -> None:
        """Compute the field's bridges (and the repair, once one was asked for) for the current
        input and parameters (in the worker)."""
        m = self.model
        if m.icadm is None:
            return
        self.worker.submit("field", jobs.bridges_job(self.find, m.icadm, m.params, self.runner))
        if m.repair_wanted:
            self.worker.submit("repair", jobs.repair_job(self.repair_fn, m.icadm, m.repair_params, self.runner))

    def _params_changed(self, params) -> None:
        if self.model.icadm is not None:
            self.worker.schedule("field", jobs.bridges_job(self.find, self.model.icadm, params, self.runner))
            self._schedule_repair()

    def _darning_changed(self, darning: str) -> None:
        if not self._schedule_repair():
            self.status.setText(f"Darning method: {darning} (used by Repair, F6)")

    def _schedule_repair(self) -> bool:
        m = self.model
        if m.icadm is None or not m.repair_wanted:
            return False
        self.worker.schedule("repair", jobs.repair_job(self.repair_fn, m.icadm, m.repair_params, self.runner))
        return True

    def run_repair(self) -> None:
        """Run the repair pipeline on the current input (in the worker); show its stages."""
        m = self.model
        if m.icadm is None:
            self.show_error("Nothing to repair", "Open a mesh or a demo first.")
            return
        m.repair_wanted = True
        self._show_stages_next = True
        self.worker.submit("repair", jobs.repair_job(self.repair_fn, m.icadm, m.repair_params, self.runner))

    def trace_from(self, vertex: int) -> None:
        """Trace a force line from a boundary vertex (the inspector's click), then animate it."""
        m = self.model
        if m.icadm is None:
            return
        loop, index = m.loop_of_vertex(vertex)
        omega = None
        if m.result is not None and 0 <= loop < len(getattr(m.result, "attraction", ())):
            omega = float(m.result.attraction[loop][index])
        self.inspector.set_picked({"vertex": vertex, "loop": loop, "index": index,
                                   "point": m.icadm.mesh.vertices[vertex], "omega": omega})
        self.status.setText(f"Tracing a force line from vertex {vertex}…")
        self.worker.submit("trace", jobs.trace_job(self.trace, m.icadm, m.params, vertex, self.runner))

    def cancel(self) -> None:
        if self.worker.busy:
            self.worker.cancel()
            self.status.setText("Cancelled")

    def _job_started(self, kind: str) -> None:
        self.progress.setValue(0)
        self.progress.setVisible(True)
        self.cancel_button.setEnabled(True)
        self._job_t0 = time.perf_counter()
        if kind == "field":
            self.status.setText("Computing the field and tracing force lines…")
        elif kind == "repair":
            self.status.setText("Repairing: bridges, hole splitting, darning…")

    def _job_progress(self, kind: str, frac: float) -> None:
        self.progress.setValue(int(max(0.0, min(1.0, frac)) * 1000))

    def _busy(self, busy: bool) -> None:
        self.progress.setVisible(busy)
        self.cancel_button.setEnabled(busy)

    def _job_finished(self, kind: str, result, seconds: float) -> None:
        m = self.model
        self.last_timing[kind] = seconds
        if kind == "load":
            src = self._loading
            m.set_input(result, src)
            self._remember(src.path, demo=src.demo is not None)
            self.setWindowTitle(f"Bridgefield - {src.label()}")
            s = result.mesh
            self.status.setText(f"Opened {src.label()}: {s.n_faces} faces, {len(m.frames)} boundary loops, "
                                f"{len(result.free_points)} free points")
            if self._pending_session is not None:
                data, self._pending_session = self._pending_session, None
                self._apply_session_view(data)
            self.recompute()
        elif kind == "field":
            model, params, bridges = result
            if model is not m.icadm or params != m.params:
                return  # computed for an input or parameters no longer shown
            t = time.perf_counter()
            m.set_result(bridges)
            self.last_timing["draw"] = time.perf_counter() - t
            n = len(bridges.candidates)
            arrived = sum(1 for c in bridges.candidates if c.line.arrived)
            self.status.setText(f"{n} force lines, {arrived} arrived (k_i = {params.ki:g}, {params.mode} mode)")
            self.timing.setText(f"field {seconds * 1000:.0f} ms")
        elif kind == "trace":
            model, params, vertex, line = result
            if model is not m.icadm:
                return
            m.select(-1)
            m.set_line(line, label=f"traced from vertex {vertex}", frame=0)
            self.status.setText(f"Force line from vertex {vertex}: {line.status}, {line.steps} steps")
            m.set_timeline_mode("line")
            self.timeline.play()
        elif kind == "repair":
            model, params, rep = result
            if model is not m.icadm or params != m.repair_params:
                return  # computed for an input or parameters no longer shown
            m.set_repair(rep)
            self.status.setText(self.repair_summary(rep))
            self.timing.setText(f"repair {seconds * 1000:.0f} ms")
            if getattr(self, "_show_stages_next", False):
                self._show_stages_next = False
                m.set_timeline_mode("stages")
                m.set_stage(0)
                self.timeline.play()

    @staticmethod
    def repair_summary(r) -> str:
        from algorithms.metrics import topology

        topo = topology(r.mesh.faces)
        darned = sum(h.split_by < 0 for h in r.holes)
        return (f"Repaired ({r.class_found}): {len(r.bridges)} bridges kept, {len(r.rejected)} rejected, "
                f"{darned} holes darned with {r.params.darning}, {len(r.new_faces)} new faces; "
                f"{'watertight' if topo.watertight else f'{topo.boundary_loops} boundary loops left'}")

    def _repair_shown(self, repair) -> None:
        self.act_save_repaired.setEnabled(repair is not None)
        self.act_stages.setEnabled(repair is not None)

    def _timeline_mode_shown(self, mode: str) -> None:
        self.act_stages.blockSignals(True)
        self.act_stages.setChecked(mode == "stages")
        self.act_stages.blockSignals(False)

    def _result_shown(self, result) -> None:
        if result is None and self.model.icadm is not None:
            self.timing.setText("")

    def _job_failed(self, kind: str, message: str) -> None:
        what = {"load": "Cannot open the file", "field": "The field computation failed",
                "trace": "Tracing failed", "repair": "The repair failed"}.get(kind, "Error")
        if kind == "load" and isinstance(self._pending_session, dict):
            self._pending_session = None
        self.show_error(what, message)

    def _job_cancelled(self, kind: str) -> None:
        self.status.setText(f"Cancelled ({kind})")

    # ================================================================ view
    def set_layer_visible(self, name: str, on: bool) -> None:
        for w in (self.layer_actions.get(name), self.parameters.layer_boxes.get(name)):
            if w is not None and w.isChecked() != on:
                w.blockSignals(True)
                w.setChecked(on)
                w.blockSignals(False)
        self.scene.set_layer_visible(name, on)

    def reset_camera(self) -> None:
        self.scene.layers.frame_camera()
        self.scene.request_render()

    def open_compare(self):
        from .compare import CompareWindow

        if self.model.icadm is None:
            self.show_error("Nothing to compare", "Open a mesh or a demo first.")
            return None
        if self.compare_window is not None:
            self.compare_window.close()
        self.compare_window = CompareWindow(self.model, self.find, parent=self, runner=self.runner)
        self.compare_window.show()
        return self.compare_window

    # ================================================================ messages
    def show_error(self, title: str, message: str) -> None:
        """A message in the window (not blocking); the window keeps working."""
        self.errors.append(f"{title}: {message}")
        self.status.setText(f"{title}: {message.splitlines()[0] if message else ''}")
        if self._error_box is not None:
            self._error_box.close()
        box = QMessageBox(QMessageBox.Warning, title, message.split("\n\n")[0], QMessageBox.Ok, self)
        if "\n\n" in message:
            box.setDetailedText(message)
        box.setWindowModality(Qt.NonModal)
        box.show()
        self._error_box = box

    def show_shortcuts(self) -> None:
        rows = []
        for a in self.actions():
            if not a.shortcut().isEmpty():
                rows.append(f"<tr><td><b>{a.shortcut().toString()}</b></td><td>{a.text().replace('&', '')}</td></tr>")
        rows.append("<tr><td><b>right click / P</b></td><td>pick: a bridge to select it, "
                    "a boundary point to trace from it</td></tr>")
        box = QMessageBox(QMessageBox.Information, "Shortcuts", "<table>" + "".join(rows) + "</table>",
                          QMessageBox.Ok, self)
        box.setWindowModality(Qt.NonModal)
        box.show()
        self._info_box = box

    def show_about(self) -> None:
        box = QMessageBox(QMessageBox.Information, "About Bridgefield",
                          "Bridgefield: force-line repair of incomplete triangulations "
                          "(Emelyanov & Skala 2004, Emelyanov 2010), made visible and tunable.",
                          QMessageBox.Ok, self)
        box.setWindowModality(Qt.NonModal)
        box.show()
        self._info_box = box

    # ================================================================ closing
    def shutdown(self) -> None:
        """Stop timers and workers, then the plotter (in that order)."""
        if getattr(self, "_shut", False):
            return
        self._shut = True
        self.timeline.pause()
        if self.compare_window is not None:
            self.compare_window.close()
        for w in list(self.workspaces):
            if _alive(w):
                w.close()
        self.workspaces = []
        self.worker.shutdown()  # cancels this window's calls in the shared worker processes
        self.scene.close()

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt API)
        self.shutdown()
        super().closeEvent(event)



def _alive(widget) -> bool:
    """False once Qt deleted the C++ object behind a Python wrapper (a closed workspace window)."""
    try:
        from shiboken6 import isValid

        return bool(isValid(widget))
    except ImportError:  # pragma: no cover
        return True

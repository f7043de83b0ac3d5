"""The explorer's scene, drawn into any pyvista plotter (the window's QtInteractor, a subplot of
the Compare view, or an off-screen Plotter for ``bridgefield shot``).

Layers (each a named actor, replaced or updated in place, never piled up):
``islands`` (distinct colours), ``loops``, ``free_points``, ``attraction`` (Ω on boundary points,
with its scalar bar), ``bridges`` (arrived force lines as tubes coloured by quality, with a
labelled scalar bar), ``rejected`` (lines that did not arrive, coloured by how they ended),
``selection`` (the selected bridge), ``line`` (the force line on the timeline, drawn up to the
current step, with its normal and force as arrows at the head), ``patches`` (the faces a repair
added) and ``holes`` (the repair stage on the timeline: hole outlines and bridge chains).

Kept and rejected: before a repair, the lines that arrived are drawn as bridges; once a repair
exists, only the bridges its conflict resolution kept are tubes, the arrived lines it rejected
are thin dark lines (the Bridges table gives the reason).

Every method here must run on the GUI thread (VTK).
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from algorithms.boundary import LoopFrame, loop_frames
from algorithms.mesh import Icadm
from algorithms.records import ARRIVED, STALLED, STEP_LIMIT, TOO_WEAK, TURNED_BACK, ForceLine
from algorithms.topology import islands

from .to_pyvista import arrow, arrow_points, points, polydata, polyline_prefix, polylines, tubes

ISLAND_COLOURS = ["#c9d6df", "#f3c98b", "#a8d5a2", "#d7b4f3", "#f4a6a6", "#9fd3e6", "#e6d49f", "#b8c4f0"]
STATUS_COLOURS = {ARRIVED: "#2ca02c", TOO_WEAK: "#7f7f7f", TURNED_BACK: "#ff7f0e", STALLED: "#8c564b",
                  STEP_LIMIT: "#e377c2"}
QUALITY_CMAP = "viridis"
QUALITY_BAR = "bridge quality"
OMEGA_CMAP = "inferno"
OMEGA_BAR = "attraction index"
CONFLICT_COLOUR = "#303030"  # arrived lines the repair's conflict resolution rejected
PATCH_COLOUR = "#4e9bd1"
HOLE_COLOUR = "#ff7f0e"
CHAIN_COLOUR = "#202020"
LAYERS = ("islands", "loops", "free_points", "attraction", "bridges", "rejected", "line", "patches", "holes")
LAYER_TITLES = {"islands": "Islands", "loops": "Boundary loops", "free_points": "Free points",
                "attraction": "Attraction index Ω", "bridges": "Bridges (kept)",
                "rejected": "Rejected lines", "line": "Traced line", "patches": "Repaired patches",
                "holes": "Repair stage (holes, chains)"}
FIELD_LAYERS = ("bridges", "rejected", "line")  # hidden while the timeline plays the repair's stages


def bridge_verdicts(result, repair=None) -> tuple[np.ndarray, list[str]]:
    """Kept or not, and why, for every candidate of a BridgeSet.

    Without a repair: kept = arrived. With one: kept = an island bridge of the repair (matched by
    its end vertices), otherwise the repair's reason for rejecting it (conflict resolution).
    """
    cands = list(result.candidates) if result is not None else []
    if repair is None:
        kept = np.array([c.line.arrived for c in cands], dtype=bool)
        return kept, ["arrived" if k else c.line.status for k, c in zip(kept, cands)]
    kept_ends = {(int(b.start), int(b.end)) for b in repair.bridges if b.kind == "island"}
    why: dict[tuple[int, int], str] = {}
    for i, reason in repair.rejected:
        if 0 <= i < len(repair.lines):
            ln = repair.lines[i]
            why.setdefault((int(ln.start_vertex), int(ln.end_vertex)), reason)
    kept, reasons = [], []
    for c in cands:
        key = (int(c.line.start_vertex), int(c.line.end_vertex))
        k = c.line.arrived and key in kept_ends
        kept.append(k)
        reasons.append("kept by the repair" if k else (c.line.status if not c.line.arrived
                                                       else why.get(key, "not used by the repair")))
    return np.array(kept, dtype=bool), reasons


def kept_mask(result, repair=None) -> np.ndarray:
    """Which candidates are kept: arrived ones, or those the repair kept once one exists."""
    return bridge_verdicts(result, repair)[0]


def qualities(result) -> np.ndarray:
    return np.array([float(c.quality) for c in result.candidates], dtype=np.float64)


class SceneLayers:
    """The layers of one renderer of a plotter (``subplot`` = (row, col) for a multi-view plotter)."""

    def __init__(self, plotter, *, subplot: tuple[int, int] | None = None, bar_suffix: str = "") -> None:
        self.plotter = plotter
        self.subplot = subplot
        self.bar_suffix = bar_suffix  # scalar bar titles must be unique per plotter
        self.visible = {name: True for name in LAYERS}
        self.model: Icadm | None = None
        self.frames: list[LoopFrame] = []
        self.scale = 1.0
        self._line_mesh: pv.PolyData | None = None
        self._line: ForceLine | None = None
        self._arrows: dict[str, pv.PolyData] = {}
        self._bridge_polys: list[np.ndarray] = []
        self._edges = False  # the islands are drawn with their triangle edges
        self._fast = False  # level of detail while an animation plays (set_fast)
        self.meshes: dict[str, pv.PolyData] = {}
        self._tubes_drawn: tuple[list, pv.PolyData] | None = None  # (kept polylines, their tubes)
        self.stage_mode = False  # the timeline shows the repair's stages: field layers hidden

    # ---------------------------------------------------------------- plumbing
    def _here(self) -> None:
        if self.subplot is not None:
            self.plotter.subplot(*self.subplot)

    def _renderer(self):
        if self.subplot is None:
            return self.plotter.renderer
        return self.plotter.renderers[self.plotter.renderers.loc_to_index(self.subplot)]

    def _remove(self, name: str) -> None:
        self.meshes.pop(name, None)
        self._here()
        bar = {"bridges": QUALITY_BAR, "attraction": OMEGA_BAR}.get(name)
        if bar is not None and self.bar_title(bar) in getattr(self.plotter, "scalar_bars", {}):
            # a scalar bar keeps the range of every mapper it was made for: drop it with its actor
            self.plotter.remove_scalar_bar(self.bar_title(bar), render=False)
        self.plotter.remove_actor(name, render=False)

    def actor(self, name: str):
        return self._renderer().actors.get(name)

    def bar_title(self, base: str) -> str:
        return base + self.bar_suffix

    def _add(self, mesh, name: str, layer: str, **kw):
        self._here()
        actor = self.plotter.add_mesh(mesh, name=name, render=False, reset_camera=False, **kw)
        self.meshes[name] = mesh  # what each named actor draws (tests and exports read it)
        actor.SetVisibility(self.shown(layer))
        return actor

    def _bar_visible(self, title: str, on: bool) -> None:
        bars = getattr(self.plotter, "scalar_bars", {})
        if title in bars:
            bars[title].SetVisibility(on)

    def shown(self, layer: str) -> bool:
        """A layer is drawn when its toggle is on (field layers not while stages play)."""
        return self.visible[layer] and not (self.stage_mode and layer in FIELD_LAYERS)

    def set_visible(self, layer: str, on: bool) -> None:
        self.visible[layer] = bool(on)
        self._apply_visibility(layer)

    def _apply_visibility(self, layer: str) -> None:
        on = self.shown(layer)
        names = {"line": ("line", "line_head", "arrow_normal", "arrow_force"), "bridges": ("bridges", "selection"),
                 "holes": ("holes", "chains")}
        for name in names.get(layer, (layer,)):
            a = self.actor(name)
            if a is not None:
                a.SetVisibility(bool(on) and not (name == "selection" and self._fast))
        if layer == "attraction":
            self._bar_visible(self.bar_title(OMEGA_BAR), on)
        if layer == "bridges":
            self._bar_visible(self.bar_title(QUALITY_BAR), on)

    def set_stage_mode(self, on: bool) -> None:
        self.stage_mode = bool(on)
        for layer in (*FIELD_LAYERS, "holes"):
            self._apply_visibility(layer)

    # ---------------------------------------------------------------- the input
    def draw_model(self, model: Icadm, frames: list[LoopFrame] | None = None) -> None:
        self.model = model
        self.frames = loop_frames(model.mesh) if frames is None else frames
        mesh = model.mesh
        v = mesh.vertices
        self.scale = float(np.linalg.norm(v.max(0) - v.min(0))) if len(v) else 1.0
        for name in ("bridges", "rejected", "selection", "attraction", "line", "line_head",
                     "arrow_normal", "arrow_force", "patches", "holes", "chains"):
            self._remove(name)
        self._line_mesh = None
        self._arrows = {}
        if mesh.n_faces:
            _, lab = islands(mesh.faces)
            pd = polydata(mesh)
            pd.cell_data["island"] = lab
            colours = [ISLAND_COLOURS[i % len(ISLAND_COLOURS)] for i in range(int(lab.max()) + 1)]
            self._edges = mesh.n_faces < 20000
            self._add(pd, "islands", "islands", scalars="island", cmap=colours, categories=True,
                      show_scalar_bar=False, smooth_shading=False, show_edges=self._edges and not self._fast,
                      edge_color="#7a8793", line_width=0.5, pickable=True)
        else:
            self._remove("islands")
        if self.frames:
            self._add(polylines([f.points for f in self.frames], closed=True), "loops", "loops",
                      color="#d62728", line_width=3, render_lines_as_tubes=True, pickable=True)
        else:
            self._remove("loops")
        if len(model.free_points):
            self._add(points(model.free_points), "free_points", "free_points", color="#1f77b4",
                      point_size=9, render_points_as_spheres=True, pickable=False)
        else:
            self._remove("free_points")

    def set_fast(self, on: bool) -> bool:
        """Level of detail while an animation plays (on): the islands' triangle edges and the
        selected bridge's translucent halo (a translucent pass) hidden, the animated line marking
        the selection; off: as drawn. Returns whether anything changed."""
        changed = self._fast != bool(on)
        self._fast = bool(on)
        self._apply_visibility("bridges")
        a = self.actor("islands")
        if a is not None and self._edges:
            want = not self._fast
            if bool(a.GetProperty().GetEdgeVisibility()) != want:
                a.GetProperty().SetEdgeVisibility(want)
        return changed

    def frame_camera(self) -> None:
        self._here()
        self.plotter.reset_camera(render=False)
        self.plotter.camera.zoom(1.1)

    # ---------------------------------------------------------------- field results
    def draw_result(self, result, *, clim: tuple[float, float] | None = None, repair=None) -> None:
        """Ω on boundary points, kept bridges as tubes by quality, lines that did not arrive by
        status, arrived lines the repair rejected (when a repair is given) in dark grey."""
        for name in ("rejected", "selection"):
            self._remove(name)
        self._bridge_polys = []
        cands = list(result.candidates) if result is not None else []
        kept = kept_mask(result, repair) if cands else np.zeros(0, dtype=bool)
        q = qualities(result) if cands else np.zeros(0)
        self._bridge_polys = [np.asarray(c.line.points) for c in cands]
        self._draw_tubes([self._bridge_polys[i] for i in np.nonzero(kept)[0]], q[kept], clim)
        if result is None:
            self._remove("attraction")
            return
        # Ω on boundary points (loop order = loop_frames(model.mesh))
        att = [np.asarray(a, dtype=np.float64) for a in getattr(result, "attraction", ())]
        if not (att and len(att) == len(self.frames) and all(len(a) == len(f.points)
                                                             for a, f in zip(att, self.frames))):
            self._remove("attraction")
        elif self.actor("attraction") is not None and "attraction" in self.meshes:
            omega = np.concatenate(att)  # same points, new values: in place (no new scalar bar)
            pts = self.meshes["attraction"]
            pts.point_data["omega"][:] = omega
            pts.Modified()
            hi = float(omega.max()) or 1.0
            mapper = self.actor("attraction").mapper
            mapper.scalar_range = (0.0, hi)
            mapper.lookup_table.scalar_range = (0.0, hi)
        else:
            pts = points(np.vstack([f.points for f in self.frames]))
            pts.point_data["omega"] = np.concatenate(att)
            hi = float(pts.point_data["omega"].max()) or 1.0
            self._add(pts, "attraction", "attraction", scalars="omega", cmap=OMEGA_CMAP, clim=[0.0, hi],
                      point_size=8, render_points_as_spheres=True, pickable=False,
                      scalar_bar_args=dict(title=self.bar_title(OMEGA_BAR), vertical=True, position_x=0.87,
                                           position_y=0.08, height=0.38, width=0.05, fmt="%.3g",
                                           title_font_size=14, label_font_size=12, color="black"))
        if (~kept).any():
            idx = np.nonzero(~kept)[0]
            pd = polylines([self._bridge_polys[i] for i in idx])
            colours = [CONFLICT_COLOUR if cands[i].line.arrived else STATUS_COLOURS[cands[i].line.status] for i in idx]
            status_colour = np.array([_rgb(c) for c in colours], dtype=np.uint8)
            pd.cell_data["status_rgb"] = status_colour
            self._add(pd, "rejected", "rejected", scalars="status_rgb", rgb=True, line_width=2, opacity=0.8,
                      pickable=True)

    def _draw_tubes(self, lines: list[np.ndarray], values: np.ndarray, clim) -> None:
        """The kept bridges as tubes coloured by quality. When the lines are the ones drawn (a k_i
        edit changes the qualities, not the lines), only the colours change, in place."""
        if not lines:
            self._remove("bridges")
            self._tubes_drawn = None
            return
        lo, hi = clim if clim is not None else (float(values.min()), float(values.max()))
        if hi <= lo:
            hi = lo + (abs(lo) * 1e-3 or 1e-9)
        old = self._tubes_drawn
        actor = self.actor("bridges")
        if (actor is not None and old is not None and len(old[0]) == len(lines)
                and all(a is b or np.array_equal(a, b) for a, b in zip(old[0], lines))):
            t = old[1]
            t.point_data["quality"][:] = np.asarray(values, dtype=np.float64)[t.point_data["line"]]
            t.Modified()
            actor.mapper.scalar_range = (lo, hi)
            actor.mapper.lookup_table.scalar_range = (lo, hi)  # the scalar bar reads the table
            self._tubes_drawn = (lines, t)
            return
        t = tubes(lines, values, radius=0.0045 * self.scale, name="quality")
        self._remove("bridges")
        self._tubes_drawn = None
        if t.n_points:
            # Gouraud with the tube filter's normals: smooth_shading would draw a copy, and the
            # in-place colour update above must reach the drawn mesh
            self._add(t, "bridges", "bridges", scalars="quality", cmap=QUALITY_CMAP, clim=[lo, hi],
                      interpolation="gouraud", pickable=True, scalar_bar_args=self._quality_bar())
            self._tubes_drawn = (lines, t)

    def _quality_bar(self) -> dict:
        return dict(title=self.bar_title(QUALITY_BAR), vertical=True, position_x=0.87, position_y=0.55, height=0.38,
                    width=0.05, fmt="%.3g", title_font_size=14, label_font_size=12, color="black")

    def draw_selection(self, result, index: int) -> None:
        self._remove("selection")
        if result is None or not (0 <= index < len(result.candidates)):
            return
        line = result.candidates[index].line
        if line.steps < 2:
            return
        t = tubes([np.asarray(line.points)], np.zeros(1), radius=0.009 * self.scale, name="s")
        if not t.n_points:
            return
        self._add(t, "selection", "bridges", color="#ffdd00", opacity=0.45, pickable=False)
        self._apply_visibility("bridges")  # the translucent halo stays hidden while an animation plays

    # ---------------------------------------------------------------- the repair
    def draw_patches(self, vertices, faces) -> None:
        """The faces a repair added (or the part of them a stage shows)."""
        self._remove("patches")
        if vertices is None or faces is None or not len(faces):
            return
        self._add(polydata((vertices, faces)), "patches", "patches", color=PATCH_COLOUR, show_edges=True,
                  edge_color="#2b5d80", line_width=0.5, smooth_shading=False, pickable=False)

    def draw_repair(self, repair) -> None:
        """The final patches of a RepairResult (None removes them)."""
        if repair is None:
            self.draw_patches(None, None)
        else:
            self.draw_patches(repair.mesh.vertices, repair.mesh.faces[repair.new_faces])

    def draw_stage(self, frame) -> None:
        """One frame of the repair's stages: hole outlines, bridge chains, patches so far."""
        for name in ("holes", "chains"):
            self._remove(name)
        if frame is None:
            return
        if frame.holes:
            self._add(polylines(list(frame.holes), closed=True), "holes", "holes", color=HOLE_COLOUR, line_width=4,
                      render_lines_as_tubes=True, pickable=False)
        if frame.bridges:
            t = tubes(list(frame.bridges), np.zeros(len(frame.bridges)), radius=0.004 * self.scale, name="s")
            if t.n_points:
                self._add(t, "chains", "holes", color=CHAIN_COLOUR, pickable=False)
        self.draw_patches(frame.vertices, frame.patches)

    def nearest_bridge(self, point: np.ndarray) -> tuple[int, float]:
        """The candidate whose polyline passes nearest the point, and that distance."""
        best, dist = -1, np.inf
        p = np.asarray(point, dtype=np.float64)
        for i, poly in enumerate(self._bridge_polys):
            if len(poly):
                d = float(np.min(np.linalg.norm(poly - p, axis=1)))
                if d < dist:
                    best, dist = i, d
        return best, dist

    # ---------------------------------------------------------------- the animated line
    def set_line(self, line: ForceLine | None) -> None:
        """Put a force line on the scene (all its points; frames show a prefix of it)."""
        self._line = line
        for name in ("line", "line_head", "arrow_normal", "arrow_force"):
            self._remove(name)
        self._line_mesh = None
        self._arrows = {}
        if line is None or line.steps == 0:
            return
        self._line_mesh = polyline_prefix(np.asarray(line.points), 1)
        colour = STATUS_COLOURS.get(line.status, "black")
        self._add(self._line_mesh, "line", "line", color=colour, line_width=7, render_lines_as_tubes=True,
                  pickable=False)
        head = pv.Sphere(radius=0.012 * self.scale, center=line.points[0], theta_resolution=12, phi_resolution=12)
        self._head0 = np.asarray(head.points).copy() - line.points[0]
        self._arrows["head"] = head
        self._add(head, "line_head", "line", color="#111111", pickable=False)
        for key, colour in (("normal", "#1f3fff"), ("force", "#e00000")):
            a = arrow(line.points[0], np.array([0.0, 0.0, 1.0]), 0.08 * self.scale)
            self._arrows[key] = a
            self._add(a, f"arrow_{key}", "line", color=colour, pickable=False)

    def set_frame(self, k: int) -> None:
        """Show the line up to step k, the arrows at step k (updates arrays in place)."""
        line = self._line
        if line is None or self._line_mesh is None:
            return
        k = max(0, min(int(k), line.steps - 1))
        polyline_prefix(np.asarray(line.points), k + 1, out=self._line_mesh)
        p = line.points[k]
        self._arrows["head"].points = self._head0 + p
        n = np.asarray(line.normals[k], dtype=np.float64)
        f = np.asarray(line.forces[k], dtype=np.float64)
        for key, vec in (("normal", n), ("force", f)):
            norm = float(np.linalg.norm(vec))
            mesh = self._arrows[key]
            if norm > 0:
                mesh.points = arrow_points(p, vec / norm, 0.08 * self.scale)
            else:
                mesh.points = np.repeat(p[None], mesh.n_points, axis=0)


def _rgb(hex_colour: str) -> tuple[int, int, int]:
    h = hex_colour.lstrip("#")
    return int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16)


# kept for callers of the first version
def draw_model(plotter, model: Icadm, **_) -> SceneLayers:
    layers = SceneLayers(plotter)
    layers.draw_model(model)
    return layers


def frame_camera(plotter, model: Icadm) -> None:
    if len(model.mesh.vertices):
        plotter.reset_camera()
        plotter.camera.zoom(1.1)

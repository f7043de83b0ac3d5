"""Drawing an incomplete model into any pyvista plotter (the window's QtInteractor or an
off-screen Plotter): islands in distinct colours, boundary loops, free points.

Actors have names so that drawing again replaces them instead of piling them up.
"""

from __future__ import annotations

import numpy as np

from algorithms.boundary import loop_frames
from algorithms.mesh import Icadm
from algorithms.topology import islands

from .to_pyvista import points, polydata, polylines

ISLAND_COLOURS = ["#c9d6df", "#f3c98b", "#a8d5a2", "#d7b4f3", "#f4a6a6", "#9fd3e6", "#e6d49f", "#b8c4f0"]


def draw_model(plotter, model: Icadm, *, show_loops: bool = True, show_free: bool = True) -> None:
    mesh = model.mesh
    if mesh.n_faces:
        _, lab = islands(mesh.faces)
        pd = polydata(mesh)
        pd.cell_data["island"] = lab
        colours = [ISLAND_COLOURS[i % len(ISLAND_COLOURS)] for i in range(int(lab.max()) + 1)]
        plotter.add_mesh(pd, scalars="island", cmap=colours, categories=True, show_scalar_bar=False,
                         smooth_shading=False, name="islands", show_edges=mesh.n_faces < 20000,
                         edge_color="#7a8793", line_width=0.5)
    frames = loop_frames(mesh)
    if show_loops and frames:
        plotter.add_mesh(polylines([f.points for f in frames], closed=True), color="#d62728", line_width=4,
                         name="loops", render_lines_as_tubes=True)
    if show_free and len(model.free_points):
        plotter.add_mesh(points(model.free_points), color="#1f77b4", point_size=9,
                         render_points_as_spheres=True, name="free_points")


def frame_camera(plotter, model: Icadm) -> None:
    v = model.mesh.vertices
    if len(v):
        plotter.reset_camera()
        plotter.camera.zoom(1.1)
    _ = np  # keep numpy import for future use in camera fitting

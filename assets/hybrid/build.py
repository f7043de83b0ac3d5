"""Rebuild the hybrid spec files and index.json of this folder: python assets/hybrid/build.py"""

import json
from pathlib import Path

HERE = Path(__file__).resolve().parent

# The paper's bicubic patch (Fig. 4), i-major control points
P = [
    [(0, -1, -1), (0, -1, -0.5), (0, -1, 0.5), (0, -1, 1)],
    [(4, -1, -1), (4, -1, -0.5), (4, -1, 0.5), (4, -1, 1)],
    [(4, 1, -1), (4, 1, -0.5), (4, 1, 0.5), (4, 1, 1)],
    [(0, 1, -1), (0, 1, -0.5), (0, 1, 0.5), (0, 1, 1)],
]
P = [[list(p) for p in row] for row in P]


def write(name: str, d: dict) -> None:
    (HERE / f"{name}.json").write_text(json.dumps(d, indent=1))


write("bezier-hole", {
    "name": "bezier-hole",
    "description": "The paper's bicubic Bezier patch (Fig. 4) with the round hole of the cylinder along Ox, r = 0.4",
    "constants": {"r": 0.4},
    "surface": {"type": "bezier", "control": P},
    "trim": "r_not(circle_z(y, z, r))",
    "mesh": {"max_edge": 0.2}})
D = [row[:] for row in P]
for i in (1, 2):
    for j in (1, 2):
        D[i][j] = [7.0, P[i][j][1], P[i][j][2]]
write("dome", {
    "name": "dome",
    "description": "The paper's Bezier patch with its four interior control points pushed out to x = 7 (doubly "
                   "curved, corners still 90 degrees), same r = 0.4 hole",
    "constants": {"r": 0.4},
    "surface": {"type": "bezier", "control": D},
    "trim": "r_not(circle_z(y, z, r))",
    "mesh": {"max_edge": 0.2}})
write("interstage", {
    "name": "interstage",
    "description": "Interstage compartment (Fig. 5): a conical shell (9) with rounded-rectangle and round openings; "
                   "dimensions in metres are our choice (the paper gives none)",
    "constants": {
        "r_bottom": 1.95, "r_top": 1.55, "l": 3.0,
        "a1": 0.5, "a2": 0.8, "a3": 0.7, "a4": 0.5, "a5": 0.4, "a6": 0.6, "a7": 0.6, "a8": 0.5,
        "r1": 0.1, "r2": 0.15, "r3": 0.12, "r4": 0.1, "r5": 0.1, "r6": 0.2,
        "h1": 1.0, "h2": 2.0, "h3": 0.5, "h4": 2.2, "h5": 2.3,
        "al1": 0.0, "al2": "pi/2", "al3": "pi/4", "al4": "110*pi/180", "al5": "160*pi/180",
        "al6": "-pi/2", "al7": "30*pi/180"},
    "surface": {"type": "cone", "r1": "r_bottom", "r2": "r_top", "length": "l", "v0": "pi/4"},
    "defs": {
        "x1": "rot_x(x, z, al1)", "x2": "rot_x(x, z, al2)", "x3": "rot_x(x, z, al3)",
        "x4": "rot_x(x, z, al4)", "z4": "rot_z(x, z, al4)",
        "x5": "rot_x(x, z, al5)", "z5": "rot_z(x, z, al5)",
        "x6": "rot_x(x, z, al6)", "z6": "rot_z(x, z, al6)",
        "x7": "rot_x(x, z, al7)", "z7": "rot_z(x, z, al7)"},
    "trim": "r_not(r_or(srect(x1, y - h1, a1, a1, r1), srect(x2, y - h1, a1, a1, r1), "
            "srect(x3, y - h2, a1, a2, r2), r_and(srect(x4, y - h4, a3, a4, r3), z4), "
            "r_and(srect(x5, y - h4, a5, a6, r4), z5), r_and(srect(x6, y - h5, a7, a8, r5), z6), "
            "r_and(circle_z(x7, y - h3, r6), z7)))",
    "mesh": {"max_edge": 0.25}})
write("cylinder-windows", {
    "name": "cylinder-windows",
    "description": "A cylinder (R = 1, along Oz) cut by the crossing cylinders f1 (along Ox r = 0.5, along Oy "
                   "r = 0.4): four windows, the seam welded",
    "constants": {"rx": 0.5, "ry": 0.4},
    "surface": {"type": "cylinder", "radius": 1.0, "z0": -1.5, "z1": 1.5, "v0": "pi/4"},
    "trim": "crossing_cylinders(x, y, z, rx, ry)",
    "mesh": {"max_edge": 0.15}})
write("torus-windows", {
    "name": "torus-windows",
    "description": "A torus (R = 2, r = 0.7) with six round windows cut by three vertical cylinders; both "
                   "directions periodic, both seams welded",
    "constants": {"R": 2.0, "rw": 0.4},
    "surface": {"type": "torus", "major": "R", "minor": 0.7, "u0": 0.0, "v0": "pi/4"},
    "trim": "r_not(r_or(circle_z(x - R, y, rw), circle_z(x + R, y, rw), circle_z(x, y - R, 0.3)))",
    "mesh": {"max_edge": 0.25}})
index = {"demos": [
    {"name": "bezier-hole", "kind": "hybrid", "file": "bezier-hole.json",
     "description": "The paper's Bezier patch with an r = 0.4 round hole (Fig. 4)"},
    {"name": "interstage", "kind": "hybrid", "file": "interstage.json",
     "description": "Interstage compartment: a cone with rounded-rectangle and round openings (Fig. 5)"},
    {"name": "dome", "kind": "hybrid", "file": "dome.json",
     "description": "Doubly curved Bezier dome (interior control points pushed out) with the r = 0.4 hole"},
    {"name": "cylinder-windows", "kind": "hybrid", "file": "cylinder-windows.json",
     "description": "A cylinder cut by the crossing cylinders f1 (four windows, welded seam)"},
    {"name": "torus-windows", "kind": "hybrid", "file": "torus-windows.json",
     "description": "A torus with six windows (both directions periodic)"},
]}
(HERE / "index.json").write_text(json.dumps(index, indent=1))

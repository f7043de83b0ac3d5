"""ASCII Scene Export (ASE, 3ds Max's text scene format), the paper's output format (spec §6).

One ``*GEOMOBJECT`` with an identity node transform and a ``*MESH``: vertex list, face list
(corners A, B, C with edge-visibility flags), face normals each followed by its three vertex
normals (area-weighted). Numbers are written with 9 significant digits.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..boundary import vertex_normals
from ..io import check_output
from ..mesh import Mesh, face_normals


def _f(x: float) -> str:
    return f"{x:.9g}"


def ase_text(mesh: Mesh, *, name: str = "frep", comment: str = "bridgefield frep") -> str:
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    safe = name.replace('"', "'")
    fn = face_normals(v, f)
    vn = vertex_normals(mesh)
    out = ["*3DSMAX_ASCIIEXPORT\t200", f'*COMMENT "{comment}"', "*SCENE {",
           f'\t*SCENE_FILENAME "{safe}"', "\t*SCENE_FIRSTFRAME 0", "\t*SCENE_LASTFRAME 0",
           "\t*SCENE_FRAMESPEED 30", "\t*SCENE_TICKSPERFRAME 160", "}",
           "*GEOMOBJECT {", f'\t*NODE_NAME "{safe}"', "\t*NODE_TM {", f'\t\t*NODE_NAME "{safe}"',
           "\t\t*TM_ROW0 1.0000\t0.0000\t0.0000", "\t\t*TM_ROW1 0.0000\t1.0000\t0.0000",
           "\t\t*TM_ROW2 0.0000\t0.0000\t1.0000", "\t\t*TM_ROW3 0.0000\t0.0000\t0.0000", "\t}",
           "\t*MESH {", "\t\t*TIMEVALUE 0", f"\t\t*MESH_NUMVERTEX {len(v)}", f"\t\t*MESH_NUMFACES {len(f)}",
           "\t\t*MESH_VERTEX_LIST {"]
    out += [f"\t\t\t*MESH_VERTEX {i}\t{_f(a)}\t{_f(b)}\t{_f(c)}" for i, (a, b, c) in enumerate(v.tolist())]
    out += ["\t\t}", "\t\t*MESH_FACE_LIST {"]
    out += [f"\t\t\t*MESH_FACE {i}:\tA: {a}\tB: {b}\tC: {c}\tAB: 1\tBC: 1\tCA: 1\t*MESH_SMOOTHING 1\t*MESH_MTLID 0"
            for i, (a, b, c) in enumerate(f.tolist())]
    out += ["\t\t}", "\t\t*MESH_NORMALS {"]
    for i, (corners, n) in enumerate(zip(f.tolist(), fn.tolist())):
        out.append(f"\t\t\t*MESH_FACENORMAL {i}\t{_f(n[0])}\t{_f(n[1])}\t{_f(n[2])}")
        out += [f"\t\t\t\t*MESH_VERTEXNORMAL {c}\t{_f(vn[c, 0])}\t{_f(vn[c, 1])}\t{_f(vn[c, 2])}" for c in corners]
    out += ["\t\t}", "\t}", "}", ""]
    return "\n".join(out)


def save_ase(mesh: Mesh, path: str | Path, *, force: bool = False, name: str = "frep") -> Path:
    """Write ``mesh`` as ASE; refuses to overwrite without ``force``."""
    path = check_output(path, force=force, formats=("ase",))
    path.write_text(ase_text(mesh, name=name))
    return path

"""Reading and writing meshes and point clouds.

Meshes are read with trimesh and ``process=False`` so that unreferenced vertices (the free
points) survive. Vertices at exactly the same position are merged (STL stores every triangle apart;
a PLY or OBJ written as a triangle soup does the same): islands that touch are then seen to touch,
and normalisation decides what the shared vertex is. Every failure is an :class:`InputError`
whose message names the file and what is wrong.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .mesh import Icadm, Mesh, MeshError
from .normalize import normalize

MESH_FORMATS = ("ply", "obj", "stl", "off")
POINT_FORMATS = ("ply", "xyz", "txt", "pts")


class InputError(ValueError):
    """A file that cannot be used, with its name and the reason."""


class OutputExistsError(FileExistsError):
    """Refusing to overwrite an existing file without being asked to."""


def _suffix(path: Path) -> str:
    return path.suffix.lower().lstrip(".")


def _check_readable(path: Path, formats: tuple[str, ...], what: str) -> None:
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a {what} file")
    if _suffix(path) not in formats:
        raise InputError(f"{path}: unknown {what} format '.{_suffix(path)}' (known: {', '.join(formats)})")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: the file is empty")


def load_raw(path: str | Path) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Vertices (V, 3) and faces (F, 3) as stored, vertices at the same position merged (merge_vertices)."""
    import trimesh

    path = Path(path)
    _check_readable(path, MESH_FORMATS, "mesh")
    fmt = _suffix(path)
    try:
        loaded = trimesh.load(str(path), file_type=fmt, process=False, force="mesh",
                              maintain_order=True)
    except IndexError as exc:  # a face index beyond the vertices, or a file that ends early
        raise InputError(f"{path}: cannot read the {fmt.upper()} file: truncated, or a face index is out of "
                         f"range ({exc})") from None
    except Exception as exc:  # trimesh raises many kinds for corrupt files
        raise InputError(f"{path}: cannot read the {fmt.upper()} file ({type(exc).__name__}: {exc})") from None
    v = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64)
    f = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(v):
        v, f = merge_vertices(v, f, tolerance=1e-9 if fmt == "stl" else None)
    if not len(v):
        raise InputError(f"{path}: the mesh has no vertices")
    if not np.all(np.isfinite(v)):
        bad = int(np.flatnonzero(~np.isfinite(v).all(axis=1))[0])
        raise InputError(f"{path}: vertex {bad} has a NaN or infinite coordinate")
    if len(f) and (f.min() < 0 or f.max() >= len(v)):
        raise InputError(f"{path}: a face index is out of range (faces use {f.min()}..{f.max()}, "
                         f"{len(v)} vertices)")
    return v, f


def merge_vertices(v: NDArray[np.float64], f: NDArray[np.int64], *,
                   tolerance: float | None = None) -> tuple[NDArray, NDArray]:
    """Merge vertices at the same position, keeping the first occurrence's order: exactly the same
    (``tolerance`` None), or the same on a grid of ``tolerance`` times the bounding-box diagonal.

    STL files written by CAD tools repeat a corner with its last bits changed (featuretype.stl), so
    STL is read with a tolerance of 1e-9 of the diagonal; relative, not 9 decimals absolute, with which
    a model 1e-9 across lost every face to three points."""
    key = np.asarray(v, dtype=np.float64) + 0.0  # -0.0 and 0.0 are one position
    if tolerance is not None and len(key):
        step = tolerance * float(np.linalg.norm(np.ptp(key, axis=0)))
        if step > 0:
            key = np.round(key / step) + 0.0
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return v[np.sort(first)], rank[inv.ravel()][f]


def load_points(path: str | Path) -> NDArray[np.float64]:
    """(P, 3) points from a PLY (its vertices) or an XYZ text file (first three columns)."""
    path = Path(path)
    _check_readable(path, POINT_FORMATS, "point cloud")
    fmt = _suffix(path)
    if fmt == "ply":
        import trimesh

        try:
            pc = trimesh.load(str(path), file_type="ply", process=False)
        except Exception as exc:
            raise InputError(f"{path}: cannot read the PLY file ({type(exc).__name__}: {exc})") from None
        pts = np.asarray(getattr(pc, "vertices", np.zeros((0, 3))), dtype=np.float64)
    else:
        rows = []
        for lineno, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            words = line.split("#")[0].replace(",", " ").split()
            if not words:
                continue
            if len(words) < 3:
                raise InputError(f"{path}: line {lineno} needs x y z, found {len(words)} values")
            try:
                rows.append([float(w) for w in words[:3]])
            except ValueError:
                raise InputError(f"{path}: line {lineno} is not x y z numbers: {line.strip()[:40]!r}") from None
        pts = np.asarray(rows, dtype=np.float64).reshape(-1, 3)
    if not len(pts):
        raise InputError(f"{path}: the point cloud is empty")
    if not np.all(np.isfinite(pts)):
        raise InputError(f"{path}: a point has a NaN or infinite coordinate")
    return pts


def load_model(path: str | Path, *, points: str | Path | None = None, **normalize_options) -> Icadm:
    """Read a mesh (and an optional point cloud of extra free points) into a normalised ICADM."""
    v, f = load_raw(path)
    if not len(f) and points is None and len(v) == 0:
        raise InputError(f"{path}: the mesh is empty")
    extra = load_points(points) if points is not None else None
    try:
        return normalize(v, f, extra_points=extra, source=str(path), **normalize_options)
    except MeshError as exc:
        raise InputError(f"{path}: {exc}") from None


def check_output(path: str | Path, *, force: bool = False, formats: tuple[str, ...] = MESH_FORMATS) -> Path:
    """Validate an output path before any work: known format, folder exists, no silent overwrite."""
    path = Path(path)
    if _suffix(path) not in formats:
        raise InputError(f"{path}: unknown output format '.{_suffix(path)}' (known: {', '.join(formats)})")
    if path.exists() and not force:
        raise OutputExistsError(f"{path}: exists already (use --force to overwrite)")
    if not path.parent.exists():
        raise InputError(f"{path}: the folder {path.parent} does not exist")
    return path


def save_mesh(mesh: Mesh, path: str | Path, *, force: bool = False,
              free_points: NDArray[np.float64] | None = None) -> Path:
    """Write PLY/OBJ/STL/OFF. Free points are appended as unreferenced vertices (PLY, OBJ, OFF)."""
    import trimesh

    path = check_output(path, force=force)
    v, f = mesh.vertices, mesh.faces
    if free_points is not None and len(free_points) and _suffix(path) != "stl":
        v = np.vstack([v, free_points])
    tm = trimesh.Trimesh(v, f, process=False, validate=False)
    data = tm.export(file_type=_suffix(path))
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path, mode) as fh:
        fh.write(data)
    return path
